#include "core/registration/em_align.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <numeric>
#include <optional>
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

// Noisy pyramid (sigma 0.01 along the lines of sight), offsets along the parent's viewing axis:
// S's EM (point-to-point) at least as good as projective ICP [15], and EM with the point-to-plane
// M-step at least as good as point-to-plane ICP (mean over trials), all within a few sigma.
// (Measured: S's EM ~ projective ICP ~3 mm; the point-to-plane pair ~16 mm, their normals from
// 5 x 5 windows of sigma-0.01 noise at 0.025 spacing are noisy.)
TEST(AlignEm, NoisyPyramidEmAsGoodAsItsSingleSampleBaseline) {
  RidgeModel model;
  model.slope_y = 0.4;
  const double sigma = 0.01;
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-0.08, 0.08);
  NullProgress progress;
  CancelToken cancel;
  enum { kEmS, kIcp, kEmPlane, kIcpPlane };
  double mean_err[4] = {0, 0, 0, 0};
  const int trials = 6;
  for (int t = 0; t < trials; ++t) {
    const Scan parent = CastRidgeScan(model, RidgeViewPose(model, -15.0), sigma, rng);
    const Scan child = CastRidgeScan(model, RidgeViewPose(model, 15.0), sigma, rng);
    const Eigen::Isometry3d truth = parent.world_from_scan.inverse() * child.world_from_scan;
    const Eigen::Vector3d axis = parent.world_from_scan.linear().col(0);
    const Eigen::Isometry3d initial = parent.world_from_scan.inverse() *
                                      Perturb(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), 0.0, u(rng) * axis) *
                                      child.world_from_scan;
    for (int k = 0; k < 4; ++k) {
      EmOptions o;
      o.method = k == kEmS || k == kEmPlane ? Method::kEm : k == kIcp ? Method::kProjectiveIcp : Method::kPointToPlane;
      o.residual = k == kEmS ? EmOptions::Residual::kPointToPoint : EmOptions::Residual::kPointToPlane;
      o.sigma_m = sigma;
      o.max_iterations = 100;
      auto r = AlignEm(parent, child, initial, o, progress, cancel);
      ASSERT_TRUE(r.ok()) << r.error().ToString();
      mean_err[k] += ComparePoses(r->parent_from_child, truth).position_m / trials;
    }
  }
  std::printf("mean position error: EM (S) %.2f mm, projective ICP %.2f mm, EM (point-to-plane) %.2f mm, "
              "point-to-plane ICP %.2f mm\n", mean_err[kEmS] * 1e3, mean_err[kIcp] * 1e3, mean_err[kEmPlane] * 1e3,
              mean_err[kIcpPlane] * 1e3);
  EXPECT_LT(mean_err[kEmS], 3 * sigma);
  EXPECT_LE(mean_err[kEmS], 1.1 * mean_err[kIcp] + 1e-3);
  EXPECT_LT(mean_err[kEmPlane], 3 * sigma);
  EXPECT_LE(mean_err[kEmPlane], 1.1 * mean_err[kIcpPlane] + 1e-3);
}

// Panoramic scans of a room (lines of sight in every direction), noise along the rays: EM (its
// default point-to-plane M-step) and point-to-plane ICP recover a translated pose; EM at least as
// well as projective ICP. (With point-to-point residuals on the parent's lines of sight every
// residual y - s points through the parent's centre, so that M-step sees no torque about it.)
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

namespace scanreg {
namespace {

struct BunnyPair {
  Scan parent, child;
  Eigen::Isometry3d truth;  // parent_from_child from bun.conf
  Eigen::Vector3d centroid; // child's, child frame
};

std::optional<BunnyPair> LoadBunnyPair(const std::filesystem::path& data, const std::string& a, const std::string& b) {
  const auto dir = data / "stanford_bunny";
  auto poses = io::ReadBunConf(dir / "bun.conf");
  if (!poses) return std::nullopt;
  std::map<std::string, Eigen::Isometry3d> by;
  for (const auto& p : *poses) by[p.scan] = p.world_from_scan;
  NullProgress progress;
  CancelToken cancel;
  auto pa = io::ReadPly(dir / (a + ".ply"), progress, cancel);
  auto pb = io::ReadPly(dir / (b + ".ply"), progress, cancel);
  if (!pa || !pb) return std::nullopt;
  BunnyPair out{std::move(*pa), std::move(*pb), by[a + ".ply"].inverse() * by[b + ".ply"], Eigen::Vector3d::Zero()};
  int n = 0;
  for (std::size_t i = 0; i < out.child.size(); ++i)
    if (out.child.valid[i]) {
      out.centroid += out.child.points[i].cast<double>();
      ++n;
    }
  out.centroid /= std::max(n, 1);
  return out;
}

EmOptions BunnyOptions(Method m) {
  EmOptions o;
  o.method = m;
  o.sigma_m = 0.0005;
  o.subsample = 4;
  o.max_correspondence_m = 0.02;
  o.outlier_mad_factor = 3.0;  // occlusions: without it the pair's rms at bun.conf is 1.9 mm, with it 0.27 mm
  o.max_iterations = 100;
  o.convergence_translation_m = 1e-6;
  return o;
}

// bun045 -> bun000. From the bun.conf pose every method stays put (the poses agree with the
// data). From 5 deg / 5 mm off, point-to-plane ICP and EM with its point-to-plane M-step (the
// default) converge back; S's EM as published (point-to-point, eq. 14) and projective ICP stall
// (measured ~3 deg / 5 mm left): the Cyberware grids fit a camera whose rays are nearly parallel,
// and residuals along the parent's rays carry no lateral or torque signal.
TEST(AlignEm, StanfordBunnyPair) {
  SCANREG_REQUIRE_REALDATA(data);
  auto pair = LoadBunnyPair(data, "bun000", "bun045");
  ASSERT_TRUE(pair.has_value());
  NullProgress progress;
  CancelToken cancel;
  const Eigen::Vector3d c = pair->centroid;
  Eigen::Isometry3d perturbed = pair->truth * Perturb(c, Eigen::Vector3d(0.3, 1.0, -0.5), 5.0, Eigen::Vector3d(0.003, -0.003, 0.0025));
  const std::pair<Method, EmOptions::Residual> variants[] = {{Method::kEm, EmOptions::Residual::kPointToPlane},
                                                             {Method::kEm, EmOptions::Residual::kPointToPoint},
                                                             {Method::kProjectiveIcp, EmOptions::Residual::kPointToPlane},
                                                             {Method::kPointToPlane, EmOptions::Residual::kPointToPlane}};
  for (const auto& [m, residual] : variants) {
    EmOptions o = BunnyOptions(m);
    o.residual = residual;
    const std::string name = EmMethodName(o);
    const bool lateral = m == Method::kPointToPlane || (m == Method::kEm && residual == EmOptions::Residual::kPointToPlane);
    for (const Eigen::Isometry3d& start : {pair->truth, perturbed}) {
      auto r = AlignEm(pair->parent, pair->child, start, o, progress, cancel);
      ASSERT_TRUE(r.ok()) << r.error().ToString();
      const double e_pos = (r->parent_from_child * c - pair->truth * c).norm();
      const double e_ang = Eigen::AngleAxisd(r->parent_from_child.linear() * pair->truth.linear().transpose()).angle();
      const bool from_truth = start.isApprox(pair->truth);
      std::printf("%-24s from %s: %3d it, error %.3f mm %.3f deg, rms %.3f mm, %d pairs, overlap %.2f, cameras %s %.2f px / %s %.2f px\n",
                  name.c_str(), from_truth ? "bun.conf " : "5deg/5mm", r->iterations, e_pos * 1e3, e_ang * 180 / M_PI,
                  r->rms_m * 1e3, r->correspondences, r->overlap, GridCameraModelName(r->parent_camera.model),
                  r->parent_camera.rms_px, GridCameraModelName(r->child_camera.model), r->child_camera.rms_px);
      if (from_truth) {
        EXPECT_LT(e_pos, 0.0002) << name;
        EXPECT_LT(e_ang, 0.1 * M_PI / 180) << name;
      } else if (lateral) {
        EXPECT_LT(e_pos, 0.001) << name;
        EXPECT_LT(e_ang, 0.3 * M_PI / 180) << name;
      } else {
        EXPECT_GT(e_ang, 1.0 * M_PI / 180) << name << ": the stall this test documents is gone; update the EM default";
      }
    }
  }
}

}  // namespace
}  // namespace scanreg
