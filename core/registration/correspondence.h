// A 3D-3D keypoint correspondence between a registered (parent) scan and a new (child) scan.
#pragma once

#include <Eigen/Core>

namespace scanreg {

struct Correspondence3d {
  Eigen::Vector3d parent;  // point in the parent scanner frame, metres
  Eigen::Vector3d child;   // point in the child scanner frame, metres
  // Inlier distance of this correspondence, metres; 0: the estimator's threshold. Sources differ:
  // SIFT keypoints sit within a grid step, FPFH voxel samples within about a voxel (issue 11).
  double tolerance_m = 0.0;
};

}  // namespace scanreg
