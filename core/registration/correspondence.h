// A 3D-3D keypoint correspondence between a registered (parent) scan and a new (child) scan.
#pragma once

#include <Eigen/Core>

namespace scanreg {

struct Correspondence3d {
  Eigen::Vector3d parent;  // point in the parent scanner frame, metres
  Eigen::Vector3d child;   // point in the child scanner frame, metres
};

}  // namespace scanreg
