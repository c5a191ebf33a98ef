// Normals of points without grid neighbours (core/merge/point_normals.h): each faces the sensor that
// saw it. A wall 30 cm thick scanned from both sides by a mobile mapper: one cloud, its two faces
// facing opposite ways, which only the per-point sensor positions tell.
#include <gtest/gtest.h>

#include <random>

#include "core/merge/point_normals.h"

namespace scanreg::merge {
namespace {

TEST(PointNormals, EachPointFacesItsOwnSensor) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<Eigen::Vector3f> points, eyes;
  for (int i = 0; i < 6000; ++i) {
    const bool front = i % 2 == 0;  // front face x = 0 seen from x = +5, back face x = -0.3 from x = -5
    points.emplace_back(front ? 0.0f : -0.3f, u(rng), u(rng));
    eyes.emplace_back(front ? 5.0f : -5.0f, 0.3f * u(rng), 1.5f);
  }
  const PointNormals n = EstimatePointNormals(points, eyes, Eigen::Vector3f::Zero(), 12, CancelToken());
  ASSERT_EQ(n.normal.size(), points.size());
  int facing = 0, described = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (n.normal[i].isZero()) continue;
    ++described;
    facing += n.normal[i].dot(eyes[i] - points[i]) > 0.0f && std::abs(n.normal[i].x()) > 0.9f;
  }
  EXPECT_GT(described, 5900);
  EXPECT_EQ(facing, described);
  // One scanner for all (a scan seen from one place): every normal faces it.
  const PointNormals one = EstimatePointNormals(points, {Eigen::Vector3f(5, 0, 0)}, Eigen::Vector3f::Zero(), 12, CancelToken());
  int towards = 0;
  for (const Eigen::Vector3f& v : one.normal) towards += v.x() > 0.9f;
  EXPECT_GT(towards, 5900);
}

}  // namespace
}  // namespace scanreg::merge
