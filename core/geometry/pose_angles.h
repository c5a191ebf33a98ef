// A rotation as heading / pitch / roll (Z-Y-X Euler angles), as surveyors read a scanner's
// orientation: world_from_scan rotation R = Rz(heading) * Ry(pitch) * Rx(roll). For an upright
// scanner pitch = roll = 0 and heading is the direction of the scanner's +x axis, counter-
// clockwise from the world +x axis. Radians.
#pragma once

#include <Eigen/Geometry>

namespace scanreg {

struct HeadingPitchRoll {
  double heading = 0;  // about world z, (-pi, pi]
  double pitch = 0;    // about the once-turned y axis, [-pi/2, pi/2]
  double roll = 0;     // about the scanner's x axis, (-pi, pi]
};

HeadingPitchRoll HeadingPitchRollFromRotation(const Eigen::Matrix3d& world_from_scan);
Eigen::Matrix3d RotationFromHeadingPitchRoll(const HeadingPitchRoll& angles);

// Angle between the scanner's z axis and the world's z axis (0 for an upright scanner), [0, pi].
double TiltAngle(const Eigen::Matrix3d& world_from_scan);

}  // namespace scanreg
