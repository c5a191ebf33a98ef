// Coarse registration of a child scan to its parent from keypoint correspondences (W §4.3,
// SPEC §2 step 7): EPnP on the virtual plane inside RANSAC with 7-correspondence samples (the
// paper), or 3D-3D RANSAC with 3-point samples and a Horn/Umeyama fit (alternative).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/registration/correspondence.h"

namespace scanreg {

enum class CoarseMethod {
  kEpnp,  // W §4.3: parent 3D <-> child virtual-plane 2D, EPnP on 7-samples
  k3d,    // 3D-3D: 3-point samples, FitRigid
};

struct CoarseOptions {
  CoarseMethod method = CoarseMethod::k3d;
  int sample_size_epnp = 7;  // W §4.3: "small, but not minimal subsets of seven correspondences"; >= 4
  int max_iterations = 50000;  // cap on RANSAC hypotheses per pass
  double confidence = 0.999;   // adaptive stop: P(at least one all-inlier sample)
  // Inlier if |parent - parent_from_child * child| < this, metres. W scores 2D reprojection; we know
  // both 3D points and score the 3D distance (one threshold for both methods, in metres, and the
  // same quantity as the later consistency check). W gives no value; 0.1 m covers range noise
  // (12 mm) plus SIFT localisation at ~0.12°/px up to ~30 m.
  double inlier_threshold_m = 0.1;
  // Support needed (issue 11, item 3; replaces W-era fixed "8 agreeing" and "10 % of all"): the
  // fewest inliers such that a wrong pose reaches them by chance with probability below this, over
  // every hypothesis drawn. The chance model: a wrong pose lands a child point within the inlier
  // threshold of its matched parent point with probability 2 pi t^2 / A (A: the largest face of the
  // parent points' bounding box; 2x for structure; the surface checks after the fine step remain). Never fewer than the sample size + 2.
  double max_false_pose_probability = 1e-3;
  // Levelled scans (tilt compensator, or levelled by the caller): a hypothesis is a heading and a
  // translation from 2 correspondences (3D method only), then refined in 6-DoF when that keeps the
  // support. Both point sets must be expressed in frames whose z axis is up.
  bool levelled = false;
  // Ambiguity (repeated façades): the best pose and the best competitor that differs from it by
  // > ambiguity_distance_m in translation or > ambiguity_angle_rad in rotation; if the
  // competitor's support >= ambiguity_ratio * the best's, the result is flagged ambiguous.
  double ambiguity_ratio = 0.8;
  double ambiguity_distance_m = 0.5;
  double ambiguity_angle_rad = 0.0872664626;  // 5°
  double focal = 1000.0;  // virtual camera focal length, pixels (any value; W: "convenient K")
  std::uint64_t seed = 1;  // RANSAC's random generator: same seed, same result

  Status Validate() const;
};

struct CoarseResult {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  int inliers = 0;                  // correspondences within inlier_threshold_m of the final pose
  int required_inliers = 0;         // the support a pose needed (max_false_pose_probability)
  std::vector<int> inlier_indices;  // ascending
  int iterations = 0;               // hypotheses drawn, both passes
  double rms_m = 0.0;               // RMS 3D distance over the inliers
  bool ambiguous = false;           // a distinct pose has similar support: callers treat as failed
  std::string reason;               // why ambiguous (empty otherwise)
  // The best distinct competitor found among the outliers (whatever its support), so that callers
  // can verify both hypotheses geometrically.
  std::optional<Eigen::Isometry3d> competitor;
  int competitor_support = 0;
};

// Errors: invalid options (kInvalidArgument), fewer correspondences than a sample + 2, or fewer
// inliers than RequiredInliers (kFailed, message names the counts), cancel (kCancelled).
//
// Procedure: (1) RANSAC over all correspondences: random samples (EPnP: sample_size_epnp pairs
// whose child point is projectable, one in front of the virtual camera put first; 3D: 3 pairs),
// each hypothesis scored on all correspondences by the 3D distance (ties: lower truncated squared
// error); adaptive count, capped. (2) Local refit: FitRigid on the inliers, re-scored, repeated
// while the support grows. (3) Competitor: the same RANSAC, sampling only the best pose's outliers
// and keeping only poses distinct from the best, run just long enough to find (with `confidence`)
// a competitor reaching ambiguity_ratio * best support.
// The fewest inliers out of n correspondences (samples of `sample_size`, `hypotheses` drawn) that a
// wrong pose reaches with probability below max_false_pose_probability; the correspondences'
// parent points give the scene's extent, their widest tolerance (or the threshold) the disc.
int RequiredInliers(int n, int sample_size, long hypotheses, double inlier_threshold_m,
                    const std::vector<Correspondence3d>& correspondences, double max_false_pose_probability);

Expected<CoarseResult> EstimateCoarse(const std::vector<Correspondence3d>& correspondences,
                                      const CoarseOptions& options, const CancelToken& cancel);

}  // namespace scanreg
