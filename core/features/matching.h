// Descriptor matching with Lowe's ratio test (W §2 step 2, SPEC §2.2): for each descriptor of the
// query scan, the nearest and second-nearest descriptor of the train scan; a match is accepted if
// d1 / d2 < t_des.
//
// Search method, measured on two simulated neighbouring stations at W's size (3000 x 750, 5 m
// apart, 3220 x 2996 SIFT features; Release, 2-core machine; tests/features/matching_test.cc,
// MatchingBenchmark; with contrast_threshold 0.02, 4873 x 4548 features, in brackets):
//   kBruteForce (cv::BFMatcher): 185 matches; 0.146 s one way on 1 thread (0.40 s), 0.076 s on 2.
//   kFlann, 4 trees, 64 checks : 194 matches, all 185 exact ones plus 9 (12) extra where the true
//                                second neighbour was missed (d2 too large, ratio test fooled);
//                                index 0.022 s per scan + 0.050 s (0.083 s) one way. 128 checks:
//                                2 (5) extra at 0.10 s (0.16 s); 256 checks: 0 (1) at 0.19 s (0.30 s).
//   kExact (blocked GEMM)      : the same 185 matches as brute force; 0.090 s for BOTH directions
//                                on 1 thread (0.059 s on 2), i.e. ~0.045 s per ordered pair.
// kExact is the default: exact (FLANN at 64 checks adds ~5 % false matches) and the cheapest per
// ordered pair once both directions share one product (MatchRatioBothWays, used by MatchAllPairs).
#pragma once

#include <memory>
#include <vector>

#include "core/common/expected.h"
#include "core/features/sift.h"

namespace scanreg {

enum class MatchMethod {
  kExact,       // exact L2 by blocked matrix product |q|^2 + |t|^2 - 2 q.t (Eigen GEMM, or in integers
                // for whole-number descriptors: whole_dots.h); final d1, d2 recomputed directly. One
                // product serves both directions of a pair.
  kFlann,       // randomized KD-trees (OpenCV FLANN), approximate; index built once per scan
  kBruteForce,  // exact L2 (cv::BFMatcher knnMatch, k = 2)
};

struct MatchOptions {
  double ratio = 0.66;        // t_des (W §2: distinctive features for 0.6-0.8); accept d1 / d2 < ratio
  bool cross_check = false;   // also require the query to be the train descriptor's nearest neighbour
  MatchMethod method = MatchMethod::kExact;
  int flann_trees = 4;        // randomized KD-trees (kFlann)
  int flann_checks = 64;      // leaves visited per query (kFlann); more = closer to exact, slower
  unsigned flann_seed = 1;    // the tree randomization seed: the same seed gives the same matches

  Status Validate() const;
};

struct FeatureMatch {
  int query = -1;      // index into the query scan's keypoints
  int train = -1;      // index into the train scan's keypoints
  float distance = 0;  // L2 descriptor distance d1
};

struct TwoWayMatches {
  std::vector<FeatureMatch> a_in_b;  // query = a, train = b
  std::vector<FeatureMatch> b_in_a;  // query = b, train = a
};

// The two nearest train descriptors of one query descriptor. best = -1 when the train set has
// fewer than two descriptors.
struct TwoNearest {
  int best = -1;
  int second = -1;
  float d1 = 0;  // L2 distances, d1 <= d2
  float d2 = 0;
};

// A scan's descriptors prepared for nearest-neighbour search (a FLANN forest for kFlann). Build
// once per scan and reuse for every pair. Searching is thread-safe (const); building is
// deterministic for a given seed.
class MatchIndex {
 public:
  MatchIndex(const ScanFeatures& features, const MatchOptions& options);
  ~MatchIndex();
  MatchIndex(MatchIndex&&) noexcept;
  MatchIndex& operator=(MatchIndex&&) noexcept;
  MatchIndex(const MatchIndex&) = delete;
  MatchIndex& operator=(const MatchIndex&) = delete;

  int size() const;
  MatchMethod method() const;
  const float* Descriptor(int i) const;  // 128 floats of descriptor i
  // For each of the n descriptors (n x 128, row-major), its two nearest descriptors in this index.
  std::vector<TwoNearest> Search(const float* descriptors, int n) const;

 private:
  friend TwoWayMatches MatchRatioBothWays(const MatchIndex&, const MatchIndex&, const MatchOptions&);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Ratio-test matches of query's descriptors in train (whose index must have been built with the
// same method). With options.cross_check, query_index (query's own index) is searched too; it is
// built on the fly when null. Matches are ordered by query index.
std::vector<FeatureMatch> MatchRatio(const ScanFeatures& query, const MatchIndex& train_index,
                                     const MatchOptions& options, const MatchIndex* query_index = nullptr);

// Both directions of a pair at once: a's descriptors in b and b's in a (for kExact from a single
// distance matrix, i.e. half the cost of two MatchRatio calls). With cross_check, each list keeps
// the mutual nearest neighbours that pass the ratio test in its own direction.
TwoWayMatches MatchRatioBothWays(const MatchIndex& a, const MatchIndex& b, const MatchOptions& options);

// Convenience: builds the index of train (and of query when cross-checking) and matches.
std::vector<FeatureMatch> MatchRatio(const ScanFeatures& query, const ScanFeatures& train,
                                     const MatchOptions& options = {});

}  // namespace scanreg
