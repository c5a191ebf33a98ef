#include "core/geometry/pose_angles.h"

#include <algorithm>
#include <cmath>

namespace scanreg {

HeadingPitchRoll HeadingPitchRollFromRotation(const Eigen::Matrix3d& r) {
  HeadingPitchRoll a;
  a.pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  if (std::abs(r(2, 0)) < 1.0 - 1e-12) {
    a.heading = std::atan2(r(1, 0), r(0, 0));
    a.roll = std::atan2(r(2, 1), r(2, 2));
  } else {  // gimbal lock (pitch = +-90 deg): only heading -+ roll is defined; put it all in heading
    a.heading = std::atan2(-r(0, 1), r(1, 1));
    a.roll = 0;
  }
  return a;
}

Eigen::Matrix3d RotationFromHeadingPitchRoll(const HeadingPitchRoll& a) {
  return (Eigen::AngleAxisd(a.heading, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(a.pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(a.roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double TiltAngle(const Eigen::Matrix3d& r) { return std::acos(std::clamp(r(2, 2), -1.0, 1.0)); }

}  // namespace scanreg
