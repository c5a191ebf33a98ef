#include "core/registration/virtual_plane.h"

#include <gtest/gtest.h>

#include <Eigen/LU>

namespace scanreg {
namespace {

TEST(VirtualPlane, AnalyticPixel) {
  // 10 m ahead, 2 m to the right (y = -2), 1 m up: right of centre and above (image y grows down).
  const Eigen::Vector2d uv = ProjectToVirtualPlane({10.0, -2.0, 1.0}, 1000.0);
  EXPECT_NEAR(uv.x(), 200.0, 1e-12);
  EXPECT_NEAR(uv.y(), -100.0, 1e-12);
  // Same through the camera model K * R_cam_from_scanner * p.
  VirtualCamera cam;
  cam.focal = 1000.0;
  const Eigen::Vector3d h = cam.Intrinsics() * VirtualCamera::CameraFromScanner() * Eigen::Vector3d(10.0, -2.0, 1.0);
  EXPECT_NEAR(h.x() / h.z(), uv.x(), 1e-12);
  EXPECT_NEAR(h.y() / h.z(), uv.y(), 1e-12);
  EXPECT_NEAR(VirtualCamera::CameraFromScanner().determinant(), 1.0, 1e-12);
}

TEST(VirtualPlane, PointSymmetryMapsBackPointsOntoTheSamePlane) {
  const Eigen::Vector3d p(4.0, 1.5, -0.7);
  const Eigen::Vector2d front = ProjectToVirtualPlane(p, 800.0);
  const Eigen::Vector2d back = ProjectToVirtualPlane(-p, 800.0);
  EXPECT_NEAR((front - back).norm(), 0.0, 1e-12);
  EXPECT_TRUE(front.allFinite());
  EXPECT_FALSE(ProjectToVirtualPlane({0.0, 1.0, 0.0}, 800.0).allFinite());
}

}  // namespace
}  // namespace scanreg
