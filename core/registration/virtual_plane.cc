#include "core/registration/virtual_plane.h"

namespace scanreg {

Eigen::Vector2d ProjectToVirtualPlane(const Eigen::Vector3d& p_scanner, double focal) {
  const Eigen::Vector3d p = p_scanner.x() < 0.0 ? Eigen::Vector3d(-p_scanner) : p_scanner;  // point symmetry
  return {-p.y() / p.x() * focal, -p.z() / p.x() * focal};
}

Eigen::Matrix3d VirtualCamera::Intrinsics() const {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = focal;
  k(1, 1) = focal;
  return k;
}

Eigen::Matrix3d VirtualCamera::CameraFromScanner() {
  Eigen::Matrix3d r;
  r << 0, -1, 0,  //
      0, 0, -1,   //
      1, 0, 0;
  return r;
}

}  // namespace scanreg
