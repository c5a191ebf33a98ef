#include "core/geometry/organize.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace scanreg {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Vector3f PointAt(double az_deg, double el_deg, double range) {
  const double az = az_deg * kDeg, el = el_deg * kDeg;
  return (range * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)))
      .cast<float>();
}

double Azimuth(const Eigen::Vector3f& p) { return std::atan2(double(p.y()), double(p.x())); }
double Elevation(const Eigen::Vector3f& p) {
  return std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
}

TEST(OrganizeTest, ProjectsPointsIntoTheirAngularCellsKeepingTheNearest) {
  OrganizeOptions options;
  options.azimuth_step_rad = options.elevation_step_rad = 1.0 * M_PI / 180.0;
  options.elevation_min_rad = -30 * M_PI / 180.0;
  options.elevation_max_rad = 30 * M_PI / 180.0;
  std::vector<Eigen::Vector3f> pts;
  std::vector<float> refl;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> az(-M_PI, M_PI), el(-0.5, 0.5);
  for (int i = 0; i < 5000; ++i) {
    const double a = az(rng), e = el(rng);
    const Eigen::Vector3f dir(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
    pts.push_back(20.0f * dir);
    refl.push_back(0.2f);
    pts.push_back(10.0f * dir);  // a nearer return on the same ray wins
    refl.push_back(0.9f);
  }
  Expected<Scan> scan = OrganizeCloud(pts, refl, options, "cloud");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->cols, 360);
  EXPECT_EQ(scan->rows, 61);
  ASSERT_GT(scan->CountValid(), 3000u);
  for (int r = 0; r < scan->rows; ++r) {
    for (int c = 0; c < scan->cols; ++c) {
      if (!scan->IsValid(r, c)) continue;
      const Eigen::Vector3f& p = scan->Point(r, c);
      EXPECT_NEAR(p.norm(), 10.0f, 1e-4);
      EXPECT_FLOAT_EQ(scan->Reflectance(r, c), 0.9f);
      // The point's direction lies within half a step of its cell's angles.
      const Eigen::Vector3f los = scan->LineOfSight(r, c);
      EXPECT_LT(std::acos(std::min(1.0f, los.dot(p.normalized()))), 0.75 * M_PI / 180.0);
    }
  }
  // Moving to free neighbouring cells never spreads two returns of one ray over two cells.
  options.max_column_shift = 2;
  Expected<Scan> shifted = OrganizeCloud(pts, refl, options, "cloud");
  ASSERT_TRUE(shifted.ok()) << shifted.error().ToString();
  std::size_t far = 0;
  for (std::size_t i = 0; i < shifted->size(); ++i) far += shifted->valid[i] && shifted->points[i].norm() > 15.0f;
  EXPECT_EQ(far, 0u);
  EXPECT_GT(shifted->CountValid(), scan->CountValid());  // crowded cells found room nearby
}

TEST(OrganizeTest, RingRowsTakeTheNearestRingElevation) {
  // Four irregular rings (a multi-beam lidar), one point per degree of azimuth, elevation jitter
  // well within the ring gaps.
  const std::vector<double> rings_deg = {10.0, 5.0, -2.0, -20.0};
  OrganizeOptions options;
  for (double e : rings_deg) options.row_elevations_rad.push_back(e * kDeg);
  options.azimuth_step_rad = 1.0 * kDeg;
  std::vector<Eigen::Vector3f> pts;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 360; ++k) {
      if ((r == 0 && k == 213) || (r == 1 && k == 214)) continue;  // two gaps, filled below
      pts.push_back(PointAt(-180.0 + k + 0.5, rings_deg[r] + jitter(rng), 4.0 + 0.01 * k));
    }
  pts.push_back(PointAt(33.5, 7.6, 3.0));  // column 213, nearer to the 10 deg ring than to 5 deg
  pts.push_back(PointAt(34.5, 7.4, 3.0));  // column 214, the other way round
  std::shuffle(pts.begin(), pts.end(), rng);
  options.max_column_shift = 1;
  Expected<Scan> scan = OrganizeCloud(pts, {}, options, "rings");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  ASSERT_EQ(scan->rows, 4);
  ASSERT_EQ(scan->cols, 360);
  for (int r = 0; r < 4; ++r) EXPECT_FLOAT_EQ(scan->angles.elevation[r], float(rings_deg[r] * kDeg));
  EXPECT_EQ(scan->CountValid(), pts.size());
  for (int r = 0; r < scan->rows; ++r)
    for (int c = 0; c < scan->cols; ++c) {
      if (!scan->IsValid(r, c)) continue;
      const Eigen::Vector3f& p = scan->Point(r, c);
      EXPECT_LT(std::abs(Elevation(p) - rings_deg[r] * kDeg), 2.6 * kDeg) << r << "," << c;
      EXPECT_LT(std::abs(std::remainder(Azimuth(p) - scan->angles.azimuth[c], 2 * M_PI)), 1.5 * kDeg);
    }
  // The two extra points sit in the rows of their nearest rings.
  int found = 0;
  for (int c = 0; c < scan->cols; ++c) {
    found += scan->IsValid(0, c) && std::abs(Elevation(scan->Point(0, c)) - 7.6 * kDeg) < 1e-5;
    found += scan->IsValid(1, c) && std::abs(Elevation(scan->Point(1, c)) - 7.4 * kDeg) < 1e-5;
  }
  EXPECT_EQ(found, 2);
}

TEST(OrganizeTest, CrowdedPointsMoveToFreeColumnsInAzimuthOrder) {
  OrganizeOptions options;
  options.row_elevations_rad = {0.0};
  options.azimuth_step_rad = 1.0 * kDeg;
  // Three points in the cell of 10..11 deg, at ranges 3, 2, 4 m, and one two cells further.
  const std::vector<Eigen::Vector3f> pts = {PointAt(10.2, 0, 3), PointAt(10.5, 0, 2), PointAt(10.8, 0, 4),
                                            PointAt(12.5, 0, 5)};
  Expected<Scan> nearest = OrganizeCloud(pts, {}, options, "crowded");
  ASSERT_TRUE(nearest.ok()) << nearest.error().ToString();
  EXPECT_EQ(nearest->CountValid(), 2u);
  EXPECT_EQ(nearest->Point(0, 190), pts[1]);  // the nearest of the three keeps the cell

  options.max_column_shift = 1;
  Expected<Scan> moved = OrganizeCloud(pts, {}, options, "crowded");
  ASSERT_TRUE(moved.ok()) << moved.error().ToString();
  ASSERT_EQ(moved->CountValid(), 4u);
  // 10.2 and 10.5 move one column left to make room for 10.8; the order along the row holds.
  EXPECT_EQ(moved->Point(0, 189), pts[0]);
  EXPECT_EQ(moved->Point(0, 190), pts[1]);
  EXPECT_EQ(moved->Point(0, 191), pts[2]);
  EXPECT_EQ(moved->Point(0, 192), pts[3]);
  EXPECT_EQ(*CloudProjection(pts).CountKept(options), 4u);

  // Two returns along one ray stay one cell: the nearer.
  const std::vector<Eigen::Vector3f> echoes = {PointAt(20.5, 0, 7), PointAt(20.5, 0, 3)};
  Expected<Scan> echo = OrganizeCloud(echoes, {}, options, "echoes");
  ASSERT_TRUE(echo.ok()) << echo.error().ToString();
  EXPECT_EQ(echo->CountValid(), 1u);
  EXPECT_EQ(echo->Point(0, 200), echoes[1]);
}

TEST(OrganizeTest, PartialAzimuthSpanAcrossTheBackOfTheScanner) {
  // Columns from 170 deg to 190 deg (= -170 deg): a sensor looking along -x.
  OrganizeOptions options;
  options.row_elevations_rad = {0.0};
  options.azimuth_step_rad = 1.0 * kDeg;
  options.azimuth_start_rad = 170.0 * kDeg;
  options.azimuth_span_rad = 20.0 * kDeg;
  std::vector<Eigen::Vector3f> pts;
  for (int k = 0; k < 20; ++k) pts.push_back(PointAt(170.5 + k, 0.0, 2.0));
  pts.push_back(PointAt(0.0, 0.0, 2.0));  // in front of the scanner: outside the grid
  Expected<Scan> scan = OrganizeCloud(pts, {}, options, "back");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  ASSERT_EQ(scan->cols, 20);
  EXPECT_EQ(scan->CountValid(), 20u);
  for (int c = 0; c < 20; ++c) {
    EXPECT_NEAR(scan->angles.azimuth[c], (170.5 + c) * kDeg, 1e-5);  // increasing, past pi
    ASSERT_TRUE(scan->IsValid(0, c));
    EXPECT_EQ(scan->Point(0, c), pts[c]);
    EXPECT_GT(scan->LineOfSight(0, c).dot(pts[c].normalized()), std::cos(0.01 * kDeg));
  }
}

TEST(OrganizeTest, RejectsNonsenseOptionsAndEmptyClouds) {
  OrganizeOptions bad;
  bad.azimuth_step_rad = 0.0;
  EXPECT_FALSE(OrganizeCloud({Eigen::Vector3f(1, 0, 0)}, {}, bad, "x").ok());
  OrganizeOptions rising;
  rising.row_elevations_rad = {0.1, 0.2};
  EXPECT_FALSE(rising.Validate().ok());
  OrganizeOptions far_shift;
  far_shift.max_column_shift = 17;
  EXPECT_FALSE(far_shift.Validate().ok());
  OrganizeOptions options;
  Expected<Scan> empty = OrganizeCloud({Eigen::Vector3f(NAN, 0, 0)}, {}, options, "nan-only");
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("nan-only"), std::string::npos);
  Expected<Scan> mismatch = OrganizeCloud({Eigen::Vector3f(1, 0, 0)}, {0.5f, 0.5f}, options, "refl");
  EXPECT_FALSE(mismatch.ok());
}

}  // namespace
}  // namespace scanreg
