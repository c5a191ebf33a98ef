#include "core/registration/point_index.h"

#include <gtest/gtest.h>

#include <random>

namespace scanreg {
namespace {

TEST(PointIndex, MatchesBruteForce) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  std::vector<Eigen::Vector3d> pts;
  const Eigen::Vector3d far_origin(500000.0, 5400000.0, 100.0);  // UTM-sized: precision kept
  for (int i = 0; i < 500; ++i) pts.push_back(far_origin + Eigen::Vector3d(u(rng), u(rng), u(rng)));
  const PointIndex index(pts);
  EXPECT_EQ(index.size(), 500u);
  for (int q = 0; q < 50; ++q) {
    const Eigen::Vector3d query = far_origin + Eigen::Vector3d(u(rng), u(rng), u(rng));
    int best = 0;
    for (int i = 1; i < 500; ++i)
      if ((pts[i] - query).squaredNorm() < (pts[best] - query).squaredNorm()) best = i;
    double d2 = -1.0;
    EXPECT_EQ(index.Nearest(query, 100.0, &d2), best);
    EXPECT_NEAR(d2, (pts[best] - query).squaredNorm(), 1e-4);
    EXPECT_EQ(index.KNearest(query, 3).front(), best);
    EXPECT_EQ(index.KNearest(query, 3).size(), 3u);
  }
  EXPECT_EQ(index.Nearest(far_origin + Eigen::Vector3d(100.0, 0.0, 0.0), 1.0), -1);
  EXPECT_EQ(PointIndex({}).Nearest(Eigen::Vector3d::Zero(), 1.0), -1);
}

}  // namespace
}  // namespace scanreg
