#include "core/georef/sphere_targets.h"

#include <gtest/gtest.h>

#include "core/simulate/project_sim.h"
#include "core/simulate/scanner.h"
#include "core/simulate/scene.h"

namespace scanreg::georef {
namespace {

constexpr double kRadius = 0.0725;

// A yard: ground, a wall 25 m away, poles of the spheres' own radius (which must not count as
// spheres), and spheres on tripods at 5, 10 and 15 m.
struct Yard {
  Scene scene;
  std::vector<Eigen::Vector3d> spheres{{5.0, 0.6, 1.4}, {-3.0, 9.5, 1.3}, {2.0, -14.8, 1.6}};
};

Yard MakeYard() {
  Yard y;
  const int grey = y.scene.AddTexture(SurfaceTexture::Uniform(0.4f)), white = y.scene.AddTexture(SurfaceTexture::Uniform(0.85f));
  y.scene.AddRectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 60, 60, grey);
  y.scene.AddRectangle(Eigen::Vector3d(25, 0, 3), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 30, 3, grey);
  for (const Eigen::Vector3d& c : y.spheres) {
    y.scene.AddSphere(c, kRadius, white);
    y.scene.AddCylinder({c.x(), c.y()}, 0.012, 0.0, c.z() - 0.06, grey);
  }
  y.scene.AddCylinder({7.0, -4.0}, kRadius, 0.0, 2.5, grey);  // a pole as thick as a sphere
  y.scene.AddBox(Eigen::Vector3d(-8, -6, 0.5), Eigen::Vector3d(1, 0.5, 0.5), 0.3, grey);
  y.scene.Build();
  return y;
}

// A modern scanner's target scan: 0.06° steps, 2 mm range noise, mixed pixels at edges.
Scan ScanYard(const Yard& y, const Eigen::Isometry3d& pose) {
  ScannerOptions o;
  o.cols = 6000;
  o.rows = 667;
  o.elevation_min_deg = -20;
  o.elevation_max_deg = 20;
  o.range_noise_m = 0.002;
  NullProgress progress;
  CancelToken cancel;
  auto scan = SimulateScan(y.scene, pose, o, "yard", progress, cancel);
  EXPECT_TRUE(scan.ok());
  return std::move(scan).value();
}

TEST(SphereTargets, CentresWithinAMillimetreUpTo15m) {
  const Yard y = MakeYard();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 1.6);
  pose.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Scan scan = ScanYard(y, pose);
  CancelToken cancel;
  SphereTargetOptions o;
  o.radius_m = kRadius;
  auto found = DetectSphereTargets(scan, o, cancel);
  ASSERT_TRUE(found.ok()) << found.error().message;
  for (const DetectedSphere& d : *found)
    std::printf("sphere at %.4f %.4f %.4f (%.2f m): %d points, rms %.2f mm, coverage %.2f, sigma %.2f mm\n",
                d.center.x(), d.center.y(), d.center.z(), d.center.norm(), d.points, d.rms_m * 1000, d.coverage,
                d.sigma_m * 1000);
  ASSERT_EQ(found->size(), y.spheres.size()) << "every sphere, and not the pole of the same radius";
  for (std::size_t k = 0; k < y.spheres.size(); ++k) {
    const Eigen::Vector3d truth = pose.inverse() * y.spheres[k];  // sorted by range, as the spheres are
    const double error = ((*found)[k].center - truth).norm();
    EXPECT_LT(error, 0.001) << "sphere at " << truth.norm() << " m: " << error * 1000 << " mm off, "
                            << (*found)[k].points << " points";
    EXPECT_GT((*found)[k].sigma_m, 0.0);
    EXPECT_LT((*found)[k].sigma_m, 0.002);
  }
}

TEST(SphereTargets, AStreetWithoutTargetsHasNone) {
  SimulatedProjectOptions o;
  o.stations = 1;
  NullProgress progress;
  CancelToken cancel;
  auto scans = SimulateProject(o, progress, cancel);
  ASSERT_TRUE(scans.ok());
  SphereTargetOptions t;
  auto found = DetectSphereTargets(scans->front(), t, cancel);
  ASSERT_TRUE(found.ok());
  EXPECT_TRUE(found->empty()) << found->size() << " spheres found in a street of poles, cars and walls; first at "
                              << (found->empty() ? Eigen::Vector3d::Zero() : found->front().center).transpose();
}

TEST(SphereTargets, AFitOfExactPointsReturnsTheCentre) {
  const Eigen::Vector3d c(3, -2, 1);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 50; ++i) {
    const double a = 0.1 * i, b = 0.05 * i;
    pts.push_back(c + 0.5 * Eigen::Vector3d(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b)));
  }
  double rms = 1;
  const Eigen::Vector3d got = FitSphereCenter(pts, 0.5, c + Eigen::Vector3d(0.05, -0.04, 0.03), &rms);
  EXPECT_LT((got - c).norm(), 1e-9);
  EXPECT_LT(rms, 1e-9);
}

TEST(SphereTargets, NonsenseOptionsAndUnorganizedScansAreRefused) {
  CancelToken cancel;
  Scan scan("flat", 1, 100);
  SphereTargetOptions o;
  EXPECT_FALSE(DetectSphereTargets(scan, o, cancel).ok());
  o.radius_m = -1;
  Scan grid("grid", 10, 10);
  EXPECT_FALSE(DetectSphereTargets(grid, o, cancel).ok());
}

}  // namespace
}  // namespace scanreg::georef
