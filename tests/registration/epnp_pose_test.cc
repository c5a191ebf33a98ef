#include "core/registration/epnp_pose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/geometry/transform.h"

namespace scanreg {
namespace {

TEST(EpnpPose, ExactWithPointsOnBothSidesOfTheVirtualCamera) {
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  truth.linear() = Eigen::AngleAxisd(2.5, Eigen::Vector3d(0.05, -0.02, 1.0).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(-6.0, 3.0, 0.4);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-20.0, 20.0), z(-2.0, 6.0);
  std::vector<Eigen::Vector3d> parent, child;
  while (child.size() < 7) {
    const Eigen::Vector3d c(u(rng), u(rng), z(rng));
    if (std::abs(c.x()) < 2.0) continue;
    child.push_back(c);
    parent.push_back(truth * c);
  }
  // First pair in front of the camera (x > 0), as EstimateCoarse arranges.
  auto front = std::find_if(child.begin(), child.end(), [](const Eigen::Vector3d& c) { return c.x() > 0.0; });
  ASSERT_NE(front, child.end());
  const auto k = front - child.begin();
  std::swap(child[0], child[k]);
  std::swap(parent[0], parent[k]);
  int behind = 0;
  for (const auto& c : child) behind += c.x() < 0.0;
  ASSERT_GT(behind, 0);
  const auto pose = EpnpParentFromChild(parent, child, 1000.0);
  ASSERT_TRUE(pose.has_value());
  const PoseError e = ComparePoses(*pose, truth);
  EXPECT_LT(e.position_m, 1e-6);
  EXPECT_LT(e.angle_rad, 1e-7);
  // Contract: the first pair must be in front of the camera; fewer than 4 pairs fail.
  std::swap(child[0], child[std::find_if(child.begin(), child.end(), [](const auto& c) { return c.x() < 0; }) - child.begin()]);
  EXPECT_FALSE(EpnpParentFromChild(parent, child, 1000.0).has_value());
  EXPECT_FALSE(EpnpParentFromChild({parent[0], parent[1], parent[2]}, {child[0], child[1], child[2]}, 1000.0));
}

}  // namespace
}  // namespace scanreg
