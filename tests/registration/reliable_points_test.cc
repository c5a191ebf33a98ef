#include "core/registration/reliable_points.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scanreg {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A wall 5 m ahead, 10 cm per cell: P(r, c) = (5, 0.1 c - 0.5, 0.5 - 0.1 r), linear in (r, c).
Scan PlanarGrid() {
  Scan s("plane", 10, 10);
  for (int r = 0; r < 10; ++r)
    for (int c = 0; c < 10; ++c) s.Set(r, c, Eigen::Vector3f(5.0f, 0.1f * c - 0.5f, 0.5f - 0.1f * r), 0.5f);
  return s;
}

TEST(ReliablePoints, ExactBilinearValueOnAPlane) {
  const Scan s = PlanarGrid();
  const auto conf = ConfidenceMap(s, ReliabilityOptions{});
  EXPECT_EQ(conf[s.Index(4, 4)], 1);
  EXPECT_EQ(conf[s.Index(0, 4)], 0);  // border row: neighbourhood incomplete
  EXPECT_EQ(conf[s.Index(4, 0)], 0);  // border column of a non-panoramic grid
  const auto p = InterpolatePoint(s, conf, 3.25f, 4.5f);
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - Eigen::Vector3f(5.0f, -0.175f, 0.05f)).norm(), 0.0f, 1e-6f);
  // On an integer pixel: the raster point itself.
  const auto q = InterpolatePoint(s, conf, 5.0f, 5.0f);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR((*q - s.Point(5, 5)).norm(), 0.0f, 1e-6f);
}

TEST(ReliablePoints, AnyInvalidNeighbourGivesNothing) {
  Scan s = PlanarGrid();
  s.Clear(4, 4);
  const auto conf = ConfidenceMap(s, ReliabilityOptions{});
  EXPECT_FALSE(InterpolatePoint(s, {}, 3.5f, 3.5f).has_value());   // (4,4) is one of the four
  EXPECT_FALSE(InterpolatePoint(s, {}, 4.0f, 4.9f).has_value());   // also
  EXPECT_TRUE(InterpolatePoint(s, {}, 5.5f, 5.5f).has_value());    // validity only: fine
  EXPECT_FALSE(InterpolatePoint(s, conf, 5.5f, 5.5f).has_value()); // (5,5) touches the hole: unreliable
  EXPECT_TRUE(InterpolatePoint(s, conf, 6.5f, 6.5f).has_value());
  EXPECT_FALSE(InterpolatePoint(s, conf, -0.5f, 3.0f).has_value()); // outside a non-panoramic grid
  EXPECT_FALSE(InterpolatePoint(s, conf, 3.0f, 9.5f).has_value());
}

TEST(ReliablePoints, DepthEdgeIsUnreliable) {
  Scan s = PlanarGrid();
  for (int r = 0; r < 10; ++r)
    for (int c = 5; c < 10; ++c) s.Set(r, c, Eigen::Vector3f(8.0f, 0.1f * c - 0.5f, 0.5f - 0.1f * r), 0.5f);
  const auto conf = ConfidenceMap(s, ReliabilityOptions{});
  EXPECT_EQ(conf[s.Index(4, 2)], 1);
  EXPECT_EQ(conf[s.Index(4, 4)], 0);  // 3x3 spans 5 m and 8 m: std ~1.4 m > 0.1 m
  EXPECT_EQ(conf[s.Index(4, 5)], 0);
  EXPECT_EQ(conf[s.Index(4, 7)], 1);
  EXPECT_FALSE(InterpolatePoint(s, conf, 4.5f, 4.5f).has_value());
  ReliabilityOptions loose;
  loose.max_range_std_m = 2.0;
  EXPECT_EQ(ConfidenceMap(s, loose)[s.Index(4, 4)], 1);
}

TEST(ReliablePoints, LowReflectanceIsUnreliable) {
  Scan s = PlanarGrid();
  s.reflectance[s.Index(3, 3)] = 0.001f;
  const auto conf = ConfidenceMap(s, ReliabilityOptions{});
  EXPECT_EQ(conf[s.Index(3, 3)], 0);
  EXPECT_EQ(conf[s.Index(3, 4)], 1);  // a dark neighbour does not matter, only a dark centre
  EXPECT_FALSE(InterpolatePoint(s, conf, 3.5f, 3.5f).has_value());
  ReliabilityOptions bad;
  bad.max_range_std_m = -1.0;
  EXPECT_FALSE(bad.Validate().ok());
  EXPECT_TRUE(ReliabilityOptions{}.Validate().ok());
}

TEST(ReliablePoints, AzimuthWrapsOnAFullPanorama) {
  // A cylinder of radius 5 m seen from its axis, 10° per column over the full turn.
  const int rows = 5, cols = 36;
  Scan s("pano", rows, cols);
  for (int c = 0; c < cols; ++c) s.angles.azimuth.push_back(static_cast<float>(-kPi + c * 2.0 * kPi / cols));
  for (int r = 0; r < rows; ++r) s.angles.elevation.push_back(static_cast<float>(0.2 - 0.1 * r));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const double az = s.angles.azimuth[c];
      s.Set(r, c, Eigen::Vector3f(5.0 * std::cos(az), 5.0 * std::sin(az), 0.5 - 0.5 * r), 0.5f);
    }
  ASSERT_TRUE(WrapsAzimuth(s));
  const auto conf = ConfidenceMap(s, ReliabilityOptions{});
  EXPECT_EQ(conf[s.Index(2, 0)], 1);
  EXPECT_EQ(conf[s.Index(2, cols - 1)], 1);
  const auto p = InterpolatePoint(s, conf, cols - 0.5f, 2.0f);  // between the last and the first column
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - 0.5f * (s.Point(2, cols - 1) + s.Point(2, 0))).norm(), 0.0f, 1e-5f);
  const auto q = InterpolatePoint(s, conf, -0.25f, 2.0f);
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR((*q - (0.25f * s.Point(2, cols - 1) + 0.75f * s.Point(2, 0))).norm(), 0.0f, 1e-5f);  // nearer column 0

  // Half a turn only: no wrap, the seam columns are unreliable and out of reach.
  Scan half = s;
  for (int c = 0; c < cols; ++c) half.angles.azimuth[c] = static_cast<float>(-kPi / 2 + c * kPi / cols);
  EXPECT_FALSE(WrapsAzimuth(half));
  EXPECT_EQ(ConfidenceMap(half, ReliabilityOptions{})[half.Index(2, 0)], 0);
  EXPECT_FALSE(InterpolatePoint(half, {}, cols - 0.5f, 2.0f).has_value());
}

}  // namespace
}  // namespace scanreg
