#include "core/geometry/transform.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scanreg {
namespace {

TEST(TransformTest, RowMajorRoundTrip) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  t.translation() << 1.5, -2.0, 3.25;
  const auto m = RowMajorFromIsometry(t);
  EXPECT_DOUBLE_EQ(m[3], 1.5);
  EXPECT_DOUBLE_EQ(m[7], -2.0);
  EXPECT_DOUBLE_EQ(m[15], 1.0);
  EXPECT_TRUE(IsometryFromRowMajor(m).isApprox(t, 1e-12));
}

TEST(TransformTest, RotationAngleAndPoseError) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(RotationAngle(r), 0.25, 1e-12);
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity(), b = Eigen::Isometry3d::Identity();
  a.linear() = r;
  a.translation() << 0.003, 0.004, 0;
  const PoseError e = ComparePoses(a, b);
  EXPECT_NEAR(e.position_m, 0.005, 1e-12);
  EXPECT_NEAR(e.angle_rad, 0.25, 1e-12);
}

TEST(TransformTest, ProjectToRotationRejectsReflectionsAndShears) {
  Eigen::Matrix3d out;
  EXPECT_FALSE(ProjectToRotation(Eigen::Vector3d(1, 1, -1).asDiagonal(), &out));
  Eigen::Matrix3d shear = Eigen::Matrix3d::Identity();
  shear(0, 1) = 0.5;
  EXPECT_FALSE(ProjectToRotation(shear, &out));
  Eigen::Matrix3d nearly = Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  nearly(0, 0) += 1e-5;
  ASSERT_TRUE(ProjectToRotation(nearly, &out));
  EXPECT_NEAR((out.transpose() * out - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace scanreg
