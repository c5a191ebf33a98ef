#include "core/registration/rigid_fit.h"

#include <gtest/gtest.h>

#include <random>

#include "core/geometry/transform.h"

namespace scanreg {
namespace {

Eigen::Isometry3d RandomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 10.0;
  return t;
}

TEST(RigidFit, RecoversRandomPoseExactly) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  const Eigen::Isometry3d truth = RandomPose(rng);
  std::vector<Eigen::Vector3d> src, dst;
  for (int i = 0; i < 20; ++i) {
    src.emplace_back(u(rng), u(rng), u(rng));
    dst.push_back(truth * src.back());
  }
  auto fit = FitRigid(src, dst);
  ASSERT_TRUE(fit.ok()) << fit.error().ToString();
  EXPECT_LT((fit->matrix() - truth.matrix()).norm(), 1e-9);
  EXPECT_NEAR(fit->linear().determinant(), 1.0, 1e-12);
}

TEST(RigidFit, ZeroWeightIgnoresOutlier) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  const Eigen::Isometry3d truth = RandomPose(rng);
  std::vector<Eigen::Vector3d> src, dst;
  std::vector<double> w;
  for (int i = 0; i < 10; ++i) {
    src.emplace_back(u(rng), u(rng), u(rng));
    dst.push_back(truth * src.back());
    w.push_back(1.0 + i);
  }
  dst[4] += Eigen::Vector3d(3.0, -2.0, 1.0);  // gross outlier
  w[4] = 0.0;
  auto fit = FitRigid(src, dst, w);
  ASSERT_TRUE(fit.ok());
  EXPECT_LT((fit->matrix() - truth.matrix()).norm(), 1e-9);
  auto unweighted = FitRigid(src, dst);
  ASSERT_TRUE(unweighted.ok());
  EXPECT_GT((unweighted->matrix() - truth.matrix()).norm(), 1e-3);  // the outlier does matter otherwise
}

TEST(RigidFit, DegenerateInputsAreErrors) {
  std::vector<Eigen::Vector3d> line, line2;
  for (int i = 0; i < 5; ++i) {
    line.emplace_back(i, 2.0 * i, -i);
    line2.push_back(line.back() + Eigen::Vector3d(1, 0, 0));
  }
  auto fit = FitRigid(line, line2);
  ASSERT_FALSE(fit.ok());
  EXPECT_NE(fit.error().message.find("collinear"), std::string::npos);
  EXPECT_FALSE(FitRigid({line[0], line[1]}, {line2[0], line2[1]}).ok());
  EXPECT_FALSE(FitRigid(line, {line2[0]}).ok());
  EXPECT_FALSE(FitRigid(line, line2, {1.0, 1.0}).ok());
}

}  // namespace
}  // namespace scanreg
