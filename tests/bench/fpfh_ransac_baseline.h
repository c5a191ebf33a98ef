// The generic pipeline a user can download today, as its authors publish it (Open3D's "global
// registration" tutorial), written with PCL's parts: voxel grid, normals (radius 2 voxels), FPFH
// (radius 5 voxels), correspondences by mutual nearest neighbour in FPFH space, RANSAC over them
// (3 samples, edge-length checker 0.9, distance checker 1.5 voxels, up to 100 000 iterations,
// confidence 0.999), then point-to-plane ICP (0.4 voxels). Issues 36 and 37 name it as the
// baseline: "FPFH at a 0.5 m voxel on a street, mutual filter, 100 k iterations".
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>

#include "core/geometry/scan.h"

namespace scanreg::bench {

struct FpfhRansacOptions {
  double voxel_m = 0.5;         // FPFH / RANSAC cloud; the radii and distances below are multiples of it
  double icp_voxel_m = 0.1;     // ICP cloud (the tutorial refines on the full cloud: this one is smaller, so faster)
  double max_range_m = 1e9;     // no range limit: the tutorial has none
  int max_iterations = 100000;
  double confidence = 0.999;
  int icp_iterations = 30;      // Open3D's ICPConvergenceCriteria default
  std::uint64_t seed = 1;
  int threads = 2;              // RANSAC hypotheses in parallel, as Open3D's OpenMP loop
};

struct FpfhRansacResult {
  bool accepted = false;         // RANSAC found a pose (Open3D returns it without a further verdict)
  double fitness = 0;            // RANSAC inliers / correspondences
  std::size_t correspondences = 0, inliers = 0;
  int iterations = 0;
  double seconds_features = 0, seconds_ransac = 0, seconds_icp = 0;
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  double Seconds() const { return seconds_features + seconds_ransac + seconds_icp; }
};

FpfhRansacResult FpfhRansacPair(const Scan& parent, const Scan& child, const FpfhRansacOptions& o);

}  // namespace scanreg::bench
