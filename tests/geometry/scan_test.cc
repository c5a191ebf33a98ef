#include "core/geometry/scan.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scanreg {
namespace {

// A 40 x 90 panoramic grid of a sphere of radius 10 around the scanner.
Scan SphereScan() {
  Scan scan("sphere", 40, 90);
  for (int r = 0; r < scan.rows; ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      if ((r * 7 + c) % 11 == 0) continue;  // some empty cells
      const double el = 0.6 - r * 0.03, az = -M_PI + (c + 0.5) * 2 * M_PI / scan.cols;
      scan.Set(r, c, Eigen::Vector3f(10 * std::cos(el) * std::cos(az), 10 * std::cos(el) * std::sin(az), 10 * std::sin(el)),
               0.5f);
    }
  }
  return scan;
}

TEST(ScanTest, CellsAreRowMajorAndCounted) {
  Scan scan = SphereScan();
  EXPECT_EQ(scan.size(), 40u * 90u);
  EXPECT_EQ(scan.Index(2, 3), 2u * 90u + 3u);
  std::size_t expected = 0;
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 90; ++c) expected += (r * 7 + c) % 11 != 0;
  EXPECT_EQ(scan.CountValid(), expected);
  scan.Clear(0, 1);
  EXPECT_FALSE(scan.IsValid(0, 1));
  EXPECT_EQ(scan.CountValid(), expected - 1);
  EXPECT_TRUE(scan.Validate().ok());
}

TEST(ScanTest, StaysWithinTwentyBytesPerCell) {
  const std::size_t bytes = sizeof(Eigen::Vector3f) + sizeof(float) + sizeof(std::uint8_t);
  EXPECT_LE(bytes, 20u);
}

TEST(ScanTest, ValidateRejectsNaNAndMismatchedArrays) {
  Scan scan = SphereScan();
  scan.points[scan.Index(5, 5)] = Eigen::Vector3f(NAN, 0, 0);
  scan.valid[scan.Index(5, 5)] = 1;
  Status s = scan.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("5,5"), std::string::npos);
  Scan broken = SphereScan();
  broken.reflectance.pop_back();
  EXPECT_FALSE(broken.Validate().ok());
}

TEST(ScanTest, EstimatedAnglesMatchTheGridAndFillEmptyColumns) {
  Scan scan = SphereScan();
  for (int r = 0; r < scan.rows; ++r) scan.Clear(r, 17);  // a whole empty column
  ASSERT_TRUE(EstimateAngularGrid(scan));
  for (int c = 0; c < scan.cols; ++c) {
    const double az = -M_PI + (c + 0.5) * 2 * M_PI / scan.cols;
    EXPECT_NEAR(std::remainder(scan.angles.azimuth[c] - az, 2 * M_PI), 0.0, 1e-4) << "column " << c;
  }
  for (int r = 0; r < scan.rows; ++r) EXPECT_NEAR(scan.angles.elevation[r], 0.6 - r * 0.03, 1e-4);
  // The line of sight from angles equals the direction to the point.
  const Eigen::Vector3f los = scan.LineOfSight(3, 4);
  EXPECT_LT((los - scan.Point(3, 4).normalized()).norm(), 1e-4);
}

TEST(ScanTest, LargeCoordinatesKeepMillimetresThroughTheDoublePose) {
  Scan scan = SphereScan();
  scan.world_from_scan.translation() << 500000.123, 5800000.456, 45.789;  // UTM-sized
  const Eigen::Vector3d world = scan.world_from_scan * scan.Point(10, 10).cast<double>();
  const Eigen::Vector3d back = scan.world_from_scan.inverse() * world;
  EXPECT_LT((back - scan.Point(10, 10).cast<double>()).norm(), 1e-6);
}

}  // namespace
}  // namespace scanreg
