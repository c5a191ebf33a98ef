// All-pairs matching and the confusion matrix (W §2 step 3, SPEC §2.3): C(i, j) = number of
// ratio-test matches of scan i's descriptors in scan j; C(i, i) = number of features of scan i.
// C is not symmetric (the ratio test is not). W's Table 1 (11 scans): diagonal 4061-7154,
// off-diagonal 17-656.
#pragma once

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "core/common/expected.h"
#include "core/common/skipped_pair.h"
#include "core/common/progress.h"
#include "core/features/matching.h"
#include "core/features/sift.h"

namespace scanreg {

struct PairMatches {
  int query_scan = -1;  // i: whose descriptors were searched
  int train_scan = -1;  // j: searched in
  std::vector<FeatureMatch> matches;  // ordered by query keypoint index
};

struct MatchTable {
  Eigen::MatrixXi confusion;       // n x n, C(i, j) as above
  std::vector<PairMatches> pairs;  // every ordered pair i != j, row-major: (0,1), (0,2), ..., (1,0), (1,2), ...
  // The matches of i's descriptors in j; nullptr when i == j or out of range.
  const PairMatches* Find(int i, int j) const;
};

// Builds one MatchIndex per scan, then matches every pair of scans in both directions in parallel
// (OpenMP over unordered pairs; see MatchRatioBothWays).
// The result does not depend on the number of threads. Cancel is checked once per pair; progress
// is reported at most ~200 times. Fails with kInvalidArgument for bad options or a scan whose
// descriptors do not match its keypoints, kCancelled when cancelled.
Expected<MatchTable> MatchAllPairs(const std::vector<ScanFeatures>& scans, const MatchOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel);

// The same for the given unordered pairs only (each listed once or twice, either way round): the
// others are left out, with C(i, j) = kSkippedPair and empty matches.
Expected<MatchTable> MatchPairs(const std::vector<ScanFeatures>& scans, const std::vector<std::pair<int, int>>& pairs,
                                const MatchOptions& options, ProgressSink& progress, const CancelToken& cancel);

// Only the confusion matrix of MatchAllPairs.
Expected<Eigen::MatrixXi> ConfusionMatrix(const std::vector<ScanFeatures>& scans, const MatchOptions& options,
                                          ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg
