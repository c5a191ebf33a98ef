#include "core/simulate/scanner.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace scanreg {
namespace {

ScannerOptions Small(int cols = 720, int rows = 180) {
  ScannerOptions o;
  o.cols = cols;
  o.rows = rows;
  return o;
}

Eigen::Isometry3d StationAt(double x, double y, double z, double heading) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  pose.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return pose;
}

Scan Simulate(const Scene& scene, const Eigen::Isometry3d& pose, const ScannerOptions& o) {
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = SimulateScan(scene, pose, o, "test", progress, cancel);
  EXPECT_TRUE(scan.ok()) << (scan.ok() ? "" : scan.error().ToString());
  return std::move(scan).value();
}

bool BitIdentical(const Scan& a, const Scan& b) {
  return a.size() == b.size() &&
         std::memcmp(a.points.data(), b.points.data(), a.size() * sizeof(Eigen::Vector3f)) == 0 &&
         std::memcmp(a.reflectance.data(), b.reflectance.data(), a.size() * sizeof(float)) == 0 && a.valid == b.valid;
}

// The exact (double) line of sight of a cell, scanner frame, as documented in ScannerOptions.
Eigen::Vector3d ExactLineOfSight(const ScannerOptions& o, int r, int c) {
  const double az = -M_PI + (c + 0.5) * 2.0 * M_PI / o.cols;
  const double el =
      (o.elevation_max_deg - (r + 0.5) * (o.elevation_max_deg - o.elevation_min_deg) / o.rows) * M_PI / 180.0;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

TEST(ScannerTest, SameSeedIdenticalDifferentSeedDifferent) {
  const Scene scene = MakeScene(SceneOptions());
  const auto pose = StationAt(1.0, 0.5, 1.7, 0.3);
  ScannerOptions o = Small();
  const Scan a = Simulate(scene, pose, o), b = Simulate(scene, pose, o);
  EXPECT_TRUE(BitIdentical(a, b));
  o.seed = 2;
  const Scan c = Simulate(scene, pose, o);
  EXPECT_FALSE(BitIdentical(a, c));
  EXPECT_GT(a.CountValid(), a.size() / 2);
}

TEST(ScannerTest, ResultDoesNotDependOnThreadCount) {
  const Scene scene = MakeScene(SceneOptions());
  const auto pose = StationAt(-3.0, 0.0, 1.8, 2.0);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Scan one = Simulate(scene, pose, Small());
  omp_set_num_threads(std::max(2, threads));
  const Scan many = Simulate(scene, pose, Small());
  omp_set_num_threads(threads);
  EXPECT_TRUE(BitIdentical(one, many));
}

TEST(ScannerTest, AngularGridAndPoseAreFilled) {
  const Scene scene = MakeScene(SceneOptions());
  const auto pose = StationAt(0, 0, 1.7, 1.0);
  const ScannerOptions o = Small(400, 100);
  const Scan scan = Simulate(scene, pose, o);
  ASSERT_EQ(scan.angles.azimuth.size(), 400u);
  ASSERT_EQ(scan.angles.elevation.size(), 100u);
  EXPECT_NEAR(scan.angles.azimuth[0], -M_PI + M_PI / 400, 1e-6);
  EXPECT_NEAR(scan.angles.elevation[0], (50.0 - 0.45) * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(scan.angles.elevation[99], (-40.0 + 0.45) * M_PI / 180.0, 1e-6);
  EXPECT_TRUE(scan.world_from_scan.isApprox(Eigen::Isometry3d::Identity()));
  ASSERT_TRUE(scan.reference_world_from_scan.has_value());
  EXPECT_TRUE(scan.reference_world_from_scan->isApprox(pose));
  EXPECT_TRUE(scan.Validate().ok());
  for (int r = 0; r < scan.rows; r += 7)
    for (int c = 0; c < scan.cols; c += 5)
      if (scan.IsValid(r, c)) {
        EXPECT_NEAR(scan.LineOfSight(r, c).dot(scan.Point(r, c).normalized()), 1.0, 1e-6);
      }
}

TEST(ScannerTest, SkyGivesNoReturnGroundDoes) {
  Scene scene;
  scene.AddRectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 500, 500,
                     scene.AddTexture(SurfaceTexture::Uniform(0.3f)));
  scene.Build();
  const ScannerOptions o = Small(360, 90);
  const Scan scan = Simulate(scene, StationAt(0, 0, 1.7, 0), o);
  for (int r = 0; r < scan.rows; ++r) {
    const double el = scan.angles.elevation[r] * 180.0 / M_PI;
    for (int c = 0; c < scan.cols; ++c) {
      if (el > 0.0) {
        ASSERT_FALSE(scan.IsValid(r, c)) << r << "," << c;
      }
      if (el < -10.0) {
        ASSERT_TRUE(scan.IsValid(r, c)) << r << "," << c;
        EXPECT_GE(scan.Reflectance(r, c), 0.0f);
        EXPECT_LE(scan.Reflectance(r, c), 1.0f);
      }
    }
  }
}

// Range noise lies along the line of sight (S §3): compare every point with the exact
// ray-surface intersection.
TEST(ScannerTest, RangeNoiseIsAlongLineOfSightOnly) {
  const Scene scene = MakeScene(SceneOptions());
  const auto pose = StationAt(2.0, -0.7, 1.7, -0.8);
  ScannerOptions o = Small(900, 225);
  o.mixed_pixels = false;
  const Scan scan = Simulate(scene, pose, o);
  double sum = 0, sum2 = 0, across2 = 0;
  long n = 0;
  for (int r = 0; r < scan.rows; ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      const Eigen::Vector3d los = ExactLineOfSight(o, r, c);
      const auto hit = scene.Intersect(pose.translation(), pose.linear() * los, o.max_range_m);
      ASSERT_TRUE(hit.has_value());
      const Eigen::Vector3d d = scan.Point(r, c).cast<double>() - hit->range * los;
      const double along = d.dot(los);
      sum += along;
      sum2 += along * along;
      across2 += (d - along * los).squaredNorm();
      ++n;
    }
  }
  ASSERT_GT(n, 100000);
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean), across = std::sqrt(across2 / n);
  std::printf("noise along: mean %.5f m, sd %.5f m (sigma %.3f m); across RMS %.2e m; %ld points\n", mean, sd,
              o.range_noise_m, across, n);
  EXPECT_NEAR(sd, o.range_noise_m, 0.1 * o.range_noise_m);
  EXPECT_LT(std::abs(mean), 0.05 * o.range_noise_m);
  EXPECT_LT(across, 1e-4);  // float rounding only
}

// With noise off, every mixed pixel lies between its own surface and a neighbour's.
TEST(ScannerTest, MixedPixelsFloatBetweenForegroundAndBackground) {
  const Scene scene = MakeScene(SceneOptions());
  const auto pose = StationAt(0.0, 0.0, 1.7, 0.0);
  ScannerOptions o = Small(900, 225);
  o.range_noise_m = 0.0;
  const Scan scan = Simulate(scene, pose, o);
  std::vector<double> exact(scan.size(), -1.0);
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c) {
      const auto hit = scene.Intersect(pose.translation(), pose.linear() * ExactLineOfSight(o, r, c), o.max_range_m);
      if (hit) exact[scan.Index(r, c)] = hit->range;
    }
  long mixed = 0, valid = 0;
  for (int r = 1; r + 1 < scan.rows; ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      ++valid;
      const double own = exact[scan.Index(r, c)], measured = scan.Point(r, c).norm();
      if (std::abs(measured - own) < 1e-3) continue;
      ++mixed;
      bool between = false;
      for (auto [dr, dc] : {std::pair{0, 1}, {0, -1}, {1, 0}, {-1, 0}}) {
        const double other = exact[scan.Index(r + dr, (c + dc + scan.cols) % scan.cols)];
        if (other > 0 && measured >= std::min(own, other) - 1e-3 && measured <= std::max(own, other) + 1e-3)
          between = true;
      }
      EXPECT_TRUE(between) << "cell " << r << "," << c << " at " << measured << " m, surface at " << own;
    }
  }
  std::printf("mixed pixels: %ld of %ld valid cells\n", mixed, valid);
  EXPECT_GT(mixed, 200);
  EXPECT_LT(mixed, valid / 10);
}

// A wall between the scanner and a building: nothing is returned from behind the wall.
TEST(ScannerTest, OcclusionNoPointBehindWall) {
  Scene scene;
  scene.AddRectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 300, 300,
                     scene.AddTexture(SurfaceTexture::Uniform(0.3f)));
  scene.AddRectangle({6, 0, 1.5}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 2.0, 1.5,
                     scene.AddTexture(SurfaceTexture::Uniform(0.6f)));
  scene.AddBox({25, 0, 6}, {5, 15, 6}, 0.0, scene.AddTexture(SurfaceTexture::Uniform(0.5f)));
  scene.Build();
  const ScannerOptions o = Small(1440, 360);  // 0.25° steps
  const Scan scan = Simulate(scene, StationAt(0, 0, 1.7, 0), o);
  const double margin = 1.5 * 2.0 * M_PI / o.cols;  // 1.5 cells: edge cells may be mixed pixels
  const double az_max = std::atan2(2.0, 6.0) - margin;
  long on_wall = 0, on_building = 0;
  for (int r = 0; r < scan.rows; ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      const Eigen::Vector3d los = ExactLineOfSight(o, r, c);
      const Eigen::Vector3f& p = scan.Point(r, c);
      if (p.x() > 19.9) ++on_building;
      // Where the line of sight crosses the wall's plane x = 6 (inside the wall, with margin).
      if (los.x() <= 0) continue;
      const double t = 6.0 / los.x();
      const double y = t * los.y(), z = 1.7 + t * los.z();
      const double az = std::atan2(los.y(), los.x());
      const double el_lo = std::atan2(-1.7, std::hypot(6.0, y)) + margin,
                   el_hi = std::atan2(1.3, std::hypot(6.0, y)) - margin;
      const double el = std::asin(los.z());
      if (std::abs(az) < az_max && el > el_lo && el < el_hi) {
        ASSERT_TRUE(std::abs(y) < 2 && z > 0 && z < 3);
        ++on_wall;
        EXPECT_LT(p.x(), 6.0 + 6 * o.range_noise_m) << "point behind the wall at cell " << r << "," << c;
      }
    }
  }
  EXPECT_GT(on_wall, 1000);
  EXPECT_GT(on_building, 1000);
}

TEST(ScannerTest, OptionsValidateRejectsNonsense) {
  EXPECT_TRUE(ScannerOptions().Validate().ok());
  ScannerOptions o;
  o.cols = 0;
  EXPECT_FALSE(o.Validate().ok());
  o = ScannerOptions();
  o.range_noise_m = -0.01;
  EXPECT_FALSE(o.Validate().ok());
  o = ScannerOptions();
  o.elevation_min_deg = 50;
  EXPECT_FALSE(o.Validate().ok());
  EXPECT_NE(o.Validate().error().message.find("elevation"), std::string::npos);
  o = ScannerOptions();
  o.max_range_m = std::nan("");
  EXPECT_FALSE(o.Validate().ok());
  o = ScannerOptions();
  o.reflectance_noise = -1;
  EXPECT_FALSE(o.Validate().ok());
  o = ScannerOptions();
  o.cols = 100000;  // each side within its range, the panorama not (the fuzz run's crash)
  o.rows = 50000;
  ASSERT_FALSE(o.Validate().ok());
  EXPECT_NE(o.Validate().error().message.find("100 million cells"), std::string::npos);
  o.rows = 1000;
  EXPECT_TRUE(o.Validate().ok());
  NullProgress progress;
  CancelToken cancel;
  o = ScannerOptions();
  o.rows = -3;
  const auto scan = SimulateScan(Scene(), Eigen::Isometry3d::Identity(), o, "bad", progress, cancel);
  ASSERT_FALSE(scan.ok());
  EXPECT_EQ(scan.error().code, ErrorCode::kInvalidArgument);
}

TEST(ScannerTest, CancelReturnsCancelled) {
  const Scene scene = MakeScene(SceneOptions());
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  const auto scan = SimulateScan(scene, StationAt(0, 0, 1.7, 0), Small(), "c", progress, cancel);
  ASSERT_FALSE(scan.ok());
  EXPECT_EQ(scan.error().code, ErrorCode::kCancelled);
}

}  // namespace
}  // namespace scanreg
