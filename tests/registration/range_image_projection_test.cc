#include "core/registration/range_image_projection.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "core/io/ply.h"
#include "tests/registration/ridge_scans.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

using testing::CastRidgeScan;
using testing::RidgeModel;
using testing::RidgeViewPose;

TEST(RangeImageProjection, AngularGridProjectsCellsOntoThemselves) {
  RidgeModel model;
  model.slope_y = 0.2;
  std::mt19937 rng(1);
  const Scan scan = CastRidgeScan(model, RidgeViewPose(model, 20.0), 0.0, rng);
  auto proj = RangeImageProjection::Create(scan);
  ASSERT_TRUE(proj.ok()) << proj.error().ToString();
  EXPECT_EQ(proj->fit().model, GridCameraModel::kAngular);
  EXPECT_LT(proj->fit().max_px, 1e-3);
  int checked = 0;
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      double row = 0, col = 0;
      ASSERT_TRUE(proj->Project(scan.Point(r, c).cast<double>(), &row, &col));
      EXPECT_NEAR(row, r, 1e-3);
      EXPECT_NEAR(col, c, 1e-3);
      EXPECT_TRUE((scan.Point(r, c).cast<double>() - proj->LineOfSight(scan.Point(r, c).cast<double>()) *
                                                           scan.Point(r, c).norm()).norm() < 1e-5);
      ++checked;
    }
  EXPECT_GT(checked, 1000);
  EXPECT_GT(proj->valid_triangles(), checked);  // ~2 per cell
}

TEST(RangeImageProjection, InterpolatesTheMeasuredSurfaceAlongTheLineOfSight) {
  // Noise-free pyramid faces are planes: a point on a face, between vertices, is recovered
  // exactly (linear interpolation in a flat triangle), away from the edges between faces.
  RidgeModel model;
  model.slope_y = 0.2;
  std::mt19937 rng(2);
  const Eigen::Isometry3d world_from_scan = RidgeViewPose(model, -25.0);
  const Scan scan = CastRidgeScan(model, world_from_scan, 0.0, rng);
  auto proj = RangeImageProjection::Create(scan);
  ASSERT_TRUE(proj.ok());
  std::uniform_real_distribution<double> u(-0.45, 0.45);
  int found = 0;
  double worst = 0;
  for (int k = 0; k < 500; ++k) {
    const double x = u(rng), y = u(rng);
    if (std::abs(x) < 0.05 || std::abs(y) < 0.05) continue;  // stay off the face edges
    const Eigen::Vector3d world(x, y, -model.slope_x * std::abs(x) - model.slope_y * std::abs(y));
    const Eigen::Vector3d local = world_from_scan.inverse() * world;
    // Also a point displaced along the line of sight must land on the same surface point.
    const Eigen::Vector3d off = local + 0.3 * proj->LineOfSight(local);
    Eigen::Vector3d s1, s2;
    if (!proj->SurfaceAlongLineOfSight(local, &s1)) continue;
    ASSERT_TRUE(proj->SurfaceAlongLineOfSight(off, &s2));
    // On the face's plane (exact), and within a small fraction of the spacing from the point:
    // the mesh is linear in the grid, the line of sight is not.
    const Eigen::Vector3d n = world_from_scan.linear().transpose() *
                              Eigen::Vector3d(model.slope_x * (x > 0 ? 1 : -1), model.slope_y * (y > 0 ? 1 : -1), 1.0).normalized();
    const double plane_offset = n.dot(world_from_scan.inverse() * Eigen::Vector3d::Zero());
    EXPECT_NEAR(n.dot(s1), plane_offset, 1e-5);
    EXPECT_NEAR(n.dot(s2), plane_offset, 1e-5);
    worst = std::max({worst, (s1 - local).norm(), (s2 - local).norm()});
    ++found;
  }
  EXPECT_GT(found, 300);
  EXPECT_LT(worst, 0.05 * model.spacing);
}

TEST(RangeImageProjection, SkipsDepthDiscontinuities) {
  RidgeModel model;
  std::mt19937 rng(3);
  Scan scan = CastRidgeScan(model, RidgeViewPose(model, 0.0), 0.0, rng);
  auto before = RangeImageProjection::Create(scan);
  ASSERT_TRUE(before.ok());
  // Push the right half 0.5 m back along its lines of sight: a step edge between columns.
  const int split = scan.cols / 2;
  int rows_with_step = 0;
  for (int r = 0; r < scan.rows; ++r) {
    bool any = false;
    for (int c = split; c < scan.cols; ++c)
      if (scan.IsValid(r, c)) {
        scan.points[scan.Index(r, c)] *= (scan.Point(r, c).norm() + 0.5f) / scan.Point(r, c).norm();
        any = any || (scan.IsValid(r, split - 1));
      }
    rows_with_step += any;
  }
  auto after = RangeImageProjection::Create(scan);
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(before->valid_triangles() - after->valid_triangles(), 2 * (rows_with_step - 1));
  for (int r = 0; r + 1 < scan.rows; ++r) {
    Eigen::Vector3d p;
    EXPECT_FALSE(after->SurfaceAt(r + 0.5, split - 0.5, &p) && scan.IsValid(r, split - 1) && scan.IsValid(r, split));
  }
}

// A pinhole grid (projective camera) and an orthographic grid (affine camera), without angles.
Scan GridScan(bool pinhole) {
  Scan scan("grid", 30, 40);
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c) {
      const double depth = 1.0 + 0.2 * std::sin(0.3 * c) + 0.1 * std::cos(0.2 * r);
      Eigen::Vector3d p;
      if (pinhole) {
        p = depth * Eigen::Vector3d((c - 20.0) / 50.0, (r - 15.0) / 50.0, 1.0) + Eigen::Vector3d(0.1, -0.2, 0.3);
      } else {
        p = Eigen::Vector3d(0.01 * c, 0.012 * r, depth);
      }
      scan.Set(r, c, p.cast<float>(), 1.0f);
    }
  return scan;
}

TEST(RangeImageProjection, FitsAProjectiveOrAnAffineCameraToGridsWithoutAngles) {
  const Scan pin = GridScan(true);
  auto p = RangeImageProjection::Create(pin);
  ASSERT_TRUE(p.ok()) << p.error().ToString();
  EXPECT_EQ(p->fit().model, GridCameraModel::kProjective);
  EXPECT_LT(p->fit().rms_px, 1e-3);
  EXPECT_GT(p->fit().affine_rms_px, 0.05);
  // The line of sight passes through the camera centre (0.1, -0.2, 0.3).
  const Eigen::Vector3d q = pin.Point(7, 9).cast<double>();
  EXPECT_LT((q - Eigen::Vector3d(0.1, -0.2, 0.3)).normalized().dot(p->LineOfSight(q)) - 1.0, 1e-9);
  EXPECT_GT((q - Eigen::Vector3d(0.1, -0.2, 0.3)).normalized().dot(p->LineOfSight(q)), 1.0 - 1e-6);

  const Scan ortho = GridScan(false);
  auto a = RangeImageProjection::Create(ortho);
  ASSERT_TRUE(a.ok()) << a.error().ToString();
  EXPECT_EQ(a->fit().model, GridCameraModel::kAffine);
  EXPECT_LT(a->fit().rms_px, 1e-3);
  EXPECT_GT(a->LineOfSight(Eigen::Vector3d::Zero()).z(), 1.0 - 1e-6);
  Eigen::Vector3d s;
  ASSERT_TRUE(a->SurfaceAt(10.0, 20.0, &s));
  EXPECT_LT((s - ortho.Point(10, 20).cast<double>()).norm(), 1e-6);
}

TEST(RangeImageProjection, StanfordRangeGridCameraFit) {
  SCANREG_REQUIRE_REALDATA(data);
  NullProgress progress;
  CancelToken cancel;
  for (const char* name : {"bun000", "bun045", "bun090", "bun180", "bun270", "bun315", "chin", "top2"}) {
    Expected<Scan> scan = io::ReadPly(data / "stanford_bunny" / (std::string(name) + ".ply"), progress, cancel);
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    auto proj = RangeImageProjection::Create(*scan);
    ASSERT_TRUE(proj.ok()) << proj.error().ToString();
    const CameraFitReport& f = proj->fit();
    std::printf("%s: %s camera, rms %.3f px (max %.2f), projective %.3f px, affine %.3f px, %d cells, %d triangles\n",
                name, GridCameraModelName(f.model), f.rms_px, f.max_px, f.projective_rms_px, f.affine_rms_px, f.cells,
                proj->valid_triangles());
    EXPECT_LT(f.rms_px, 1.5) << name;  // measured 0.55-1.33 px: neither model is exact for the Cyberware grid
    EXPECT_GT(proj->valid_triangles(), f.cells);
  }
}

TEST(RangeImageProjection, OptionsRejectNonsense) {
  RangeImageOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.edge_spacing_ratio = 0.5;
  EXPECT_FALSE(o.Validate().ok());
  o = RangeImageOptions();
  o.min_edge_break_m = -1;
  EXPECT_FALSE(o.Validate().ok());
  o = RangeImageOptions();
  o.prefer_projective_ratio = 0;
  EXPECT_FALSE(o.Validate().ok());
  Scan tiny("tiny", 1, 5);
  EXPECT_FALSE(RangeImageProjection::Create(tiny).ok());
}

}  // namespace
}  // namespace scanreg
