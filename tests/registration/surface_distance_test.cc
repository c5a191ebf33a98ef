#include "core/registration/surface_distance.h"

#include <gtest/gtest.h>

#include <random>

#include "core/registration/point_index.h"

namespace scanreg {
namespace {

// Samples of the tilted plane z = 0.2 x + 0.1 y (5 cm grid, 1 mm jitter along the plane).
std::vector<Eigen::Vector3d> TiltedPlane(Eigen::Vector3d* normal) {
  *normal = Eigen::Vector3d(-0.2, -0.1, 1.0).normalized();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> jitter(-0.001, 0.001);
  std::vector<Eigen::Vector3d> pts;
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; ++j) {
      const double x = 0.05 * i + jitter(rng), y = 0.05 * j + jitter(rng);
      pts.emplace_back(x, y, 0.2 * x + 0.1 * y);
    }
  return pts;
}

TEST(SurfaceDistance, PlaneDistancesNotSampleDistances) {
  Eigen::Vector3d n;
  const std::vector<Eigen::Vector3d> plane = TiltedPlane(&n);
  const PointIndex index(plane);
  // Queries between samples (2.5 cm from the nearest) at known heights along the normal.
  const Eigen::Vector3d on_plane(0.025, 0.025, 0.2 * 0.025 + 0.1 * 0.025);
  const std::vector<double> heights = {0.0, 0.004, -0.012, 0.03, 0.25};
  std::vector<Eigen::Vector3d> queries;
  for (double h : heights) queries.push_back(on_plane + h * n);
  const std::vector<double> d = PointToSurfaceDistances(index, plane, queries, 0.1);
  ASSERT_EQ(d.size(), heights.size());
  for (std::size_t i = 0; i + 1 < heights.size(); ++i) EXPECT_NEAR(d[i], std::abs(heights[i]), 5e-4) << i;
  EXPECT_LT(d.back(), 0.0);  // 25 cm off the surface: outside max_distance_m
}

TEST(SurfaceDistance, FarFromAnySampleIsOutside) {
  Eigen::Vector3d n;
  const std::vector<Eigen::Vector3d> plane = TiltedPlane(&n);
  const PointIndex index(plane);
  // On the plane's extension, 1 m beyond its edge: no sample within 10 cm.
  const std::vector<double> d = PointToSurfaceDistances(index, plane, {Eigen::Vector3d(3.0, 0.0, 0.6)}, 0.1);
  EXPECT_LT(d[0], 0.0);
  EXPECT_TRUE(PointToSurfaceDistances(index, plane, {}, 0.1).empty());
}

}  // namespace
}  // namespace scanreg
