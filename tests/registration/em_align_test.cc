#include "core/registration/em_align.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <numeric>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/io/pose_file.h"
#include "tests/registration/ridge_scans.h"
#include "tests/registration/synthetic_room.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

using testing::CastRidgeScan;
using testing::RidgeModel;
using testing::RidgeViewPose;
using Method = EmOptions::Method;

TEST(EmSampleWeights, GaussianBinMassesSumToOne) {
  const std::vector<double> w = EmSampleWeights({-0.03, -0.02, -0.01, 0.0, 0.01, 0.02, 0.03}, 0.01);
  ASSERT_EQ(w.size(), 7u);
  EXPECT_NEAR(std::accumulate(w.begin(), w.end(), 0.0), 1.0, 1e-12);
  EXPECT_NEAR(w[0], w[6], 1e-12);
  EXPECT_NEAR(w[2], w[4], 1e-12);
  // Middle bin [-sigma/2, sigma/2]: erf(0.5/sqrt2) = 0.3829.
  EXPECT_NEAR(w[3], std::erf(0.5 / std::sqrt(2.0)), 1e-12);
  // Outer bins take the tails: (-inf, -2.5 sigma].
  EXPECT_NEAR(w[0], 0.5 * std::erfc(2.5 / std::sqrt(2.0)), 1e-12);
  EXPECT_EQ(EmSampleWeights({0.0}, 1.0), std::vector<double>{1.0});
}

TEST(EmOptions, ValidateRejectsNonsense) {
  EXPECT_TRUE(EmOptions().Validate().ok());
  auto expect_bad = [](auto mutate) {
    EmOptions o;
    mutate(o);
    const Status s = o.Validate();
    EXPECT_FALSE(s.ok());
    if (!s.ok()) {
      EXPECT_EQ(s.error().code, ErrorCode::kInvalidArgument);
    }
  };
  expect_bad([](EmOptions& o) { o.sigma_m = 0; });
  expect_bad([](EmOptions& o) { o.sigma_m = std::nan(""); });
  expect_bad([](EmOptions& o) { o.sample_offsets_sigma.clear(); });
  expect_bad([](EmOptions& o) { o.sample_offsets_sigma = {0, 1, 1}; });
  expect_bad([](EmOptions& o) { o.sample_offsets_sigma = {1, 0}; });
  expect_bad([](EmOptions& o) { o.max_iterations = 0; });
  expect_bad([](EmOptions& o) { o.subsample = 0; });
  expect_bad([](EmOptions& o) { o.convergence_translation_m = -1; });
  expect_bad([](EmOptions& o) { o.max_correspondence_m = -0.1; });
  expect_bad([](EmOptions& o) { o.mesh.edge_spacing_ratio = 0; });
  expect_bad([](EmOptions& o) { o.normal_window = 0; });
}

// World offset (translation t, rotation angle_deg about axis through centre) applied to the child.
Eigen::Isometry3d Perturb(const Eigen::Vector3d& centre, const Eigen::Vector3d& axis, double angle_deg,
                          const Eigen::Vector3d& t) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(angle_deg * M_PI / 180.0, axis.normalized()).toRotationMatrix();
  p.translation() = centre - p.linear() * centre + t;
  return p;
}

// Noise-free pyramid (four planes, every translation constrained), views 45 deg apart.
// Point-to-plane recovers a general perturbation. EM and projective ICP recover an offset along
// the parent's viewing axis; a lateral offset or a rotation drives them to a wrong fixed point
// (measured: 4 cm lateral -> 0.2 m, 4 deg): their residuals all lie on the parent's lines of
// sight, so they exert no torque about the parent's centre (S Table 1's large X-std).
TEST(AlignEm, NoiseFreePyramid) {
  RidgeModel model;
  model.slope_y = 0.4;
  std::mt19937 rng(5);
  const Scan parent = CastRidgeScan(model, RidgeViewPose(model, -20.0), 0.0, rng);
  const Scan child = CastRidgeScan(model, RidgeViewPose(model, 25.0), 0.0, rng);
  const Eigen::Isometry3d truth = parent.world_from_scan.inverse() * child.world_from_scan;
  const Eigen::Vector3d parent_axis = parent.world_from_scan.linear().col(0);
  NullProgress progress;
  CancelToken cancel;
  for (Method m : {Method::kEm, Method::kProjectiveIcp, Method::kPointToPlane}) {
    const Eigen::Isometry3d world_offset =
        m == Method::kPointToPlane
            ? Perturb(Eigen::Vector3d::Zero(), Eigen::Vector3d(1, 2, 3), 1.0, Eigen::Vector3d(0.03, -0.02, 0.02))
            : Perturb(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 0.0, 0.1 * parent_axis);
    const Eigen::Isometry3d initial = parent.world_from_scan.inverse() * world_offset * child.world_from_scan;
    EmOptions o;
    o.method = m;
    o.sigma_m = 0.002;
    o.max_iterations = 200;
    o.convergence_translation_m = 1e-7;
    o.convergence_rotation_rad = 1e-7;
    auto r = AlignEm(parent, child, initial, o, progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    const PoseError e = ComparePoses(r->parent_from_child, truth);
    std::printf("%-20s %3d iterations, error %.2e m %.2e deg, rms %.2e, overlap %.2f\n", EmMethodName(m), r->iterations,
                e.position_m, e.angle_rad * 180 / M_PI, r->rms_m, r->overlap);
    EXPECT_LT(e.position_m, 3e-3) << EmMethodName(m);
    EXPECT_LT(e.angle_rad, 0.1 * M_PI / 180) << EmMethodName(m);
    EXPECT_GT(r->overlap, 0.5);
  }
}

// Panoramic scans of a room (lines of sight in every direction), noise along the rays: EM and
// projective ICP both recover a translated pose; EM at least as well. (Rotations about the
// parent's centre are not tested: with correspondences on the parent's lines of sight every
// residual y - s points through that centre, so the M-step sees no torque about it; measured,
// a 1 deg turn about the vertical stays ~1 deg for both. Point-to-plane corrects it.)
TEST(AlignEm, PanoramicRoomWithRangeNoise) {
  const double sigma = 0.01;
  Eigen::Isometry3d pa = Eigen::Isometry3d::Identity(), pb = Eigen::Isometry3d::Identity();
  pa.translation() = Eigen::Vector3d(-1.0, 0.5, 1.5);
  pb.translation() = Eigen::Vector3d(1.2, -0.6, 1.4);
  pb.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Scan parent = testing::CastRoomScan(pa, 120, 480, testing::DefaultRoom(), testing::DefaultBlocks(), sigma, 11);
  const Scan child = testing::CastRoomScan(pb, 120, 480, testing::DefaultRoom(), testing::DefaultBlocks(), sigma, 12);
  const Eigen::Isometry3d truth = pa.inverse() * pb;
  NullProgress progress;
  CancelToken cancel;
  std::map<Method, double> pos, ang;
  for (Method m : {Method::kEm, Method::kProjectiveIcp, Method::kPointToPlane}) {
    double worst_pos = 0, worst_ang = 0;
    for (int trial = 0; trial < 3; ++trial) {
      const Eigen::Isometry3d initial =
          pa.inverse() *
          Perturb(pb.translation(), Eigen::Vector3d(trial, 1, 2 - trial), 0.0, Eigen::Vector3d(0.1, -0.1 * trial, 0.05)) * pb;
      EmOptions o;
      o.method = m;
      o.sigma_m = sigma;
      o.subsample = 4;
      o.max_correspondence_m = 0.2;
      o.max_iterations = 300;
      auto r = AlignEm(parent, child, initial, o, progress, cancel);
      ASSERT_TRUE(r.ok()) << r.error().ToString();
      const PoseError e = ComparePoses(r->parent_from_child, truth);
      worst_pos = std::max(worst_pos, e.position_m);
      worst_ang = std::max(worst_ang, e.angle_rad);
    }
    std::printf("%-20s worst error %.2f mm %.4f deg\n", EmMethodName(m), worst_pos * 1e3, worst_ang * 180 / M_PI);
    pos[m] = worst_pos;
    ang[m] = worst_ang;
  }
  EXPECT_LT(pos[Method::kPointToPlane], 0.002);
  EXPECT_LT(ang[Method::kPointToPlane], 0.02 * M_PI / 180);
  EXPECT_LE(pos[Method::kEm], 1.2 * pos[Method::kProjectiveIcp] + 1e-3);
  EXPECT_LE(ang[Method::kEm], 1.2 * ang[Method::kProjectiveIcp] + 1e-4);
}

TEST(AlignEm, FailsCleanlyWithoutOverlapAndWhenCancelled) {
  RidgeModel model;
  std::mt19937 rng(6);
  const Scan parent = CastRidgeScan(model, RidgeViewPose(model, 0.0), 0.0, rng);
  const Scan child = CastRidgeScan(model, RidgeViewPose(model, 10.0), 0.0, rng);
  Eigen::Isometry3d far = parent.world_from_scan.inverse() * child.world_from_scan;
  far.translation() += Eigen::Vector3d(0, 50, 0);
  NullProgress progress;
  CancelToken cancel;
  auto r = AlignEm(parent, child, far, EmOptions(), progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kFailed);
  cancel.Cancel();
  auto c = AlignEm(parent, child, parent.world_from_scan.inverse() * child.world_from_scan, EmOptions(), progress, cancel);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code, ErrorCode::kCancelled);
}

}  // namespace
}  // namespace scanreg
