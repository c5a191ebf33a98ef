#include "core/geometry/organize.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace scanreg {
namespace {

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
}

TEST(OrganizeTest, RejectsNonsenseOptionsAndEmptyClouds) {
  OrganizeOptions bad;
  bad.azimuth_step_rad = 0.0;
  EXPECT_FALSE(OrganizeCloud({Eigen::Vector3f(1, 0, 0)}, {}, bad, "x").ok());
  OrganizeOptions options;
  Expected<Scan> empty = OrganizeCloud({Eigen::Vector3f(NAN, 0, 0)}, {}, options, "nan-only");
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("nan-only"), std::string::npos);
}

}  // namespace
}  // namespace scanreg
