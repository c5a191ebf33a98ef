// EPnP (Lepetit et al. 2009, via OpenCV) on the virtual plane of the child scan (W §4.3): the pose
// of the child scanner from parent 3D points and the child's virtual-plane image points.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace scanreg {

// parent: points in the parent scanner frame; child: the same points in the child scanner frame,
// of which only the virtual-plane projections (virtual_plane.h, point symmetry for x < 0) are
// used. Needs >= 4 pairs, none with child x == 0. The first pair must have child.x() > 0: it fixes
// the sign of EPnP's solution (see virtual_plane.h). Returns parent_from_child, or nullopt when
// EPnP fails or its result is not finite.
std::optional<Eigen::Isometry3d> EpnpParentFromChild(const std::vector<Eigen::Vector3d>& parent,
                                                     const std::vector<Eigen::Vector3d>& child, double focal);

}  // namespace scanreg
