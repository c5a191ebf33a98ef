// PCL's own registration pipelines, the baselines of the benchmark (brief: "compare against PCL's
// FPFH / K-4PCS / ICP in the same run"): FPFH + SampleConsensusPrerejective + ICP, and PCL's
// KFPCSInitialAlignment (keypoint-based 4-points congruent sets, made for TLS scans) + ICP.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>

#include "core/geometry/scan.h"

namespace scanreg::bench {

// The brief's starting point was one 0.1 m cloud for everything (normals r 0.3, FPFH r 0.5, SAC
// distance 0.25 m). At 3000 x 750 that cloud has ~10^5 points and PCL's prerejective RANSAC scores
// every hypothesis that passes the polygon test on all of them (one k-d tree query per point): a
// 1000 x 250 pair ran for minutes. The usual remedy (Open3D / PCL tutorials): the global stage on a
// coarser cloud with radii scaled to it (normals 2x, FPFH 5x, distance 2.5x the voxel), ICP on the
// fine cloud; points beyond 30 m dropped; 20000 iterations instead of 50000 to bound the time
struct PclOptions {
  double max_range_m = 30.0;     // points farther from the scanner are dropped (sparse, no stable normals)
  double fine_voxel_m = 0.1;     // ICP cloud
  double coarse_voxel_m = 0.4;   // FPFH / SAC cloud
  double normal_radius_m = 0.8;
  double fpfh_radius_m = 2.0;
  int max_iterations = 20000;
  int samples = 3;
  int randomness = 5;
  float similarity = 0.9f;
  double sac_max_distance_m = 1.0;
  float inlier_fraction = 0.25f;
  double icp_max_distance_m = 0.2;
  int icp_iterations = 50;
  double kfpcs_voxel_m = 2.0;  // K-4PCS keypoints: the coarse cloud on this grid
};

struct PclPairResult {
  double seconds_features = 0, seconds_sac = 0, seconds_icp = 0;
  bool converged = false;  // the global stage's own verdict (PCL's hasConverged)
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  std::size_t parent_points = 0, child_points = 0, parent_coarse_points = 0, child_coarse_points = 0;
};

PclPairResult PclRegisterPair(const Scan& parent, const Scan& child, const PclOptions& o);

// K-4PCS (Theiler et al. 2014, PCL's KFPCSInitialAlignment) on keypoints of the coarse clouds, then
// the same ICP. seconds_sac holds the K-4PCS time. PCL's K-4PCS does not keep its own time limit
// (measured: over 5 minutes on one 1000x250 street pair with a 30 s limit), so it runs in a child
// process (this program re-executed, see RunKfpcsChild) stopped after timeout_s: *timed_out is then
// true and the result not converged.
PclPairResult PclKfpcsPair(const Scan& parent, const Scan& child, const PclOptions& o, double timeout_s,
                           bool* timed_out);

// The child's side: K-4PCS of two PCD files, prints "converged m00 m01 ... m33" (source into target).
int RunKfpcsChild(const char* target_pcd, const char* source_pcd, double delta_m, int max_seconds);

}  // namespace scanreg::bench
