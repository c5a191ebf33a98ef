// Rigid transforms: conversions and pose comparison. Transforms are named for what they map
// (world_from_scan, target_from_source); units are metres and radians.
#pragma once

#include <Eigen/Geometry>
#include <array>

namespace scanreg {

// Row-major 4x4 <-> isometry. The rotation part is re-orthonormalised on the way in.
Eigen::Isometry3d IsometryFromRowMajor(const std::array<double, 16>& m);
std::array<double, 16> RowMajorFromIsometry(const Eigen::Isometry3d& t);

// Closest rotation (SVD) to a nearly orthonormal matrix; returns false when m is far from one
// (|m^T m - I| > tolerance) or is a reflection.
bool ProjectToRotation(const Eigen::Matrix3d& m, Eigen::Matrix3d* rotation, double tolerance = 1e-3);

// Angle of a rotation in radians, in [0, pi].
double RotationAngle(const Eigen::Matrix3d& r);

struct PoseError {
  double position_m = 0.0;  // distance between the two scanner positions
  double angle_rad = 0.0;   // angle of the relative rotation
};
// Error of an estimated world_from_scan against a reference one.
PoseError ComparePoses(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& reference);

}  // namespace scanreg
