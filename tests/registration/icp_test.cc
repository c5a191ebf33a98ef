#include <gtest/gtest.h>

#include <random>

#include "core/geometry/transform.h"
#include "core/registration/icp.h"

namespace scanreg {
namespace {

TEST(KeypointIcp, ConvergesFromCoarsePose) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(0.9, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(3.0, -1.0, 0.3);
  std::vector<Eigen::Vector3d> parent, child;
  for (int i = 0; i < 100; ++i) {
    parent.emplace_back(u(rng), u(rng), u(rng) * 0.3);
    child.push_back(truth.inverse() * parent.back());
  }
  child.emplace_back(50.0, 50.0, 0.0);  // a child keypoint with no partner
  Eigen::Isometry3d initial = truth;
  initial.translation() += Eigen::Vector3d(0.05, -0.03, 0.02);
  initial.linear() = initial.linear() * Eigen::AngleAxisd(0.005, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  CancelToken cancel;
  auto r = KeypointIcp(parent, child, initial, IcpOptions{}, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const PoseError e = ComparePoses(r->parent_from_child, truth);
  EXPECT_LT(e.position_m, 1e-6);
  EXPECT_LT(e.angle_rad, 1e-7);
  EXPECT_TRUE(r->converged);
  EXPECT_EQ(r->correspondences, 100);
  EXPECT_NEAR(r->overlap, 100.0 / 101.0, 1e-12);
  EXPECT_LT(r->rms_m, 1e-6);

  initial.translation() += Eigen::Vector3d(100.0, 0.0, 0.0);
  auto far = KeypointIcp(parent, child, initial, IcpOptions{}, cancel);
  ASSERT_FALSE(far.ok());
  EXPECT_EQ(far.error().code, ErrorCode::kFailed);
  IcpOptions bad;
  bad.max_iterations = 0;
  EXPECT_FALSE(bad.Validate().ok());
}

}  // namespace
}  // namespace scanreg
