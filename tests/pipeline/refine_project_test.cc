// Registration from the current poses (`register --coarse none`, issue 4) and the EM fine step in
// the feature-based pipeline (`--fine em`), against known poses: the Stanford bunny (bun.conf) and
// a simulated street.
#include "core/pipeline/refine_project.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/io/pose_file.h"
#include "core/simulate/project_sim.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// Four of the bunny ring scans with bun.conf as the reference; the current poses are bun.conf moved by
// `deg` about a random axis through each scan's centroid and by `mm` (bun000 stays: the root).
std::vector<Scan> PerturbedBunny(const std::filesystem::path& data, double deg, double mm) {
  const std::filesystem::path dir = data / "stanford_bunny";
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(dir / "bun.conf");
  EXPECT_TRUE(poses.ok());
  if (!poses) return {};
  std::mt19937 rng(17);
  std::normal_distribution<double> g(0.0, 1.0);
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> scans;
  for (const std::string name : {"bun000", "bun045", "bun270", "bun315"}) {
    for (const io::NamedPose& p : *poses) {
      if (p.scan != name + ".ply") continue;
      Expected<Scan> s = io::ReadPly(dir / p.scan, progress, cancel);
      EXPECT_TRUE(s.ok()) << s.error().ToString();
      if (!s) return {};
      s->name = name;
      s->reference_world_from_scan = p.world_from_scan;
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      int n = 0;
      for (std::size_t k = 0; k < s->size(); ++k)
        if (s->valid[k]) c += s->points[k].cast<double>(), ++n;
      c = p.world_from_scan * (c / n);
      Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
      if (!scans.empty()) {
        move.linear() =
            Eigen::AngleAxisd(deg / kDeg, Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
        move.translation() = c - move.linear() * c + 1e-3 * mm * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      }
      s->world_from_scan = move * p.world_from_scan;
      scans.push_back(std::move(*s));
    }
  }
  return scans;
}

RegisterOptions BunnyOptions(FineMethod fine, bool global) {
  RegisterOptions o;
  o.from_current_poses = true;
  o.fine = fine;
  o.global = global;
  o.range_sigma_m = 0.0005;     // Cyberware, ~0.5 mm
  o.overlap_distance_m = 0.01;  // a few times the start error
  o.thresholds.max_rms_m = 0.002;
  o.thresholds.weak_rms_m = 0.001;
  o.root = "bun000";
  return o;
}

// Worst position / angle error of the scans against bun.conf (relative to the root).
std::pair<double, double> WorstError(const std::vector<Scan>& scans, const std::vector<Eigen::Isometry3d>& world) {
  double pos = 0, ang = 0;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    const PoseError e = ComparePoses(world[0].inverse() * world[i], scans[0].reference_world_from_scan->inverse() *
                                                                        *scans[i].reference_world_from_scan);
    pos = std::max(pos, e.position_m);
    ang = std::max(ang, e.angle_rad);
  }
  return {pos, ang};
}

// Street-sized settings (12 mm noise, 0.10 m overlap distance, as the defaults were before they came
// from the data) on a 20 cm object make every pair "overlap": links far off can pass the surface checks. A link whose loop does not close is failed,
// so no scan is left registered far from the truth: it is unregistered with the reason instead.
TEST(RegisterFromCurrentPoses, LinksWhoseLoopsDoNotCloseAreFailedNotChained) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::vector<Scan> scans = PerturbedBunny(data, 8.0, 8.0);
  ASSERT_EQ(scans.size(), 4u);
  RegisterOptions o;
  o.range_sigma_m = 0.012;
  o.overlap_distance_m = 0.10;
  o.from_current_poses = true;
  o.fine = FineMethod::kEm;
  o.root = "bun000";
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  int wrong = 0, unregistered = 0, loop_failures = 0;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    const ScanRegistration& s = r->scans[i];
    if (!s.registered) {
      ++unregistered;
      continue;
    }
    const PoseError e =
        ComparePoses(r->scans[0].world_from_scan.inverse() * s.world_from_scan,
                     scans[0].reference_world_from_scan->inverse() * *scans[i].reference_world_from_scan);
    std::printf("%s: %.1f mm %.2f deg from bun.conf\n", s.name.c_str(), e.position_m * 1e3, e.angle_rad * kDeg);
    wrong += e.position_m > 0.005 || e.angle_rad > 2.0 / kDeg;
  }
  for (const io::LinkRecord& l : r->links) loop_failures += l.reason.find("does not close") != std::string::npos;
  std::printf("%d unregistered, %d links failed by their loop\n", unregistered, loop_failures);
  EXPECT_EQ(wrong, 0) << "a scan registered far from the truth";
}

// Street-sized settings for dense ICP on a 20 cm object cannot take a single step (5 cm samples): such a link is
// failed with that reason, not "weak: stopped at the iteration cap" after 0 iterations.
TEST(RegisterFromCurrentPoses, AFineStepThatCannotStartFailsTheLink) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::vector<Scan> scans = PerturbedBunny(data, 0.0, 0.0);  // at bun.conf
  ASSERT_EQ(scans.size(), 4u);
  RegisterOptions o;  // dense ICP, street-sized settings: 12 mm noise, 0.10 m overlap distance
  o.range_sigma_m = 0.012;
  o.overlap_distance_m = 0.10;
  o.from_current_poses = true;
  o.root = "bun000";
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  int stuck = 0;
  for (const io::LinkRecord& l : r->links) {
    if (l.iterations != 0) continue;
    ++stuck;
    EXPECT_EQ(l.status, io::LinkStatus::kFailed) << l.child << ": " << l.reason;
    EXPECT_NE(l.reason.find("could not start"), std::string::npos) << l.reason;
  }
  EXPECT_GT(stuck, 0) << "the case this test is about did not occur";
}

// Defaults that fit the data (issue 11, item 6): no noise, no overlap distance, no thresholds given.
// The scale comes from the scans (0.5 mm spacing, 5 cm extent), the reach of the refinement from how
// far apart the current poses are; both fine methods reach the README flags' accuracy (2 mm / 1°).
TEST(RegisterFromCurrentPoses, StanfordBunnyFromFiveDegreesWithDefaultOptions) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::vector<Scan> scans = PerturbedBunny(data, 5.0, 5.0);
  ASSERT_EQ(scans.size(), 4u);
  std::vector<Eigen::Isometry3d> start;
  for (const Scan& s : scans) start.push_back(s.world_from_scan);
  const auto [start_pos, start_ang] = WorstError(scans, start);
  EXPECT_GT(start_ang, 4.9 / kDeg);
  for (FineMethod fine : {FineMethod::kEm, FineMethod::kDense}) {
    RegisterOptions o;  // as a user without flags
    o.from_current_poses = true;
    o.fine = fine;
    o.root = "bun000";
    NullProgress progress;
    CancelToken cancel;
    Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    std::vector<Eigen::Isometry3d> world;
    for (const ScanRegistration& s : r->scans) {
      EXPECT_TRUE(s.registered) << FineMethodName(fine) << " " << s.name << ": " << s.reason;
      world.push_back(s.world_from_scan);
    }
    const auto [pos, ang] = WorstError(scans, world);
    std::printf("bunny defaults --coarse none --fine %s: worst %.2f mm %.3f deg (start %.2f mm %.2f deg)\n",
                FineMethodName(fine), pos * 1e3, ang * kDeg, start_pos * 1e3, start_ang * kDeg);
    EXPECT_LT(pos, 0.002);
    EXPECT_LT(ang, 1.0 / kDeg);
  }
}

// The ten bunny scans from identity starts (no .conf), default options: FPFH on the geometry alone
// (the PLYs carry no reflectance), with every length taken from the data (0.55 mm spacing, 5 cm
// extent); issue 11 asks 2 mm / 1 deg of bun.conf.
TEST(RegisterScans, StanfordBunnyFromIdentityByGeometryAlone) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::filesystem::path dir = data / "stanford_bunny";
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(dir / "bun.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> scans;
  for (const io::NamedPose& p : *poses) {
    Expected<Scan> s = io::ReadPly(dir / p.scan, progress, cancel);
    ASSERT_TRUE(s.ok()) << s.error().ToString();
    s->name = p.scan.substr(0, p.scan.find('.'));
    s->reference_world_from_scan = p.world_from_scan;
    scans.push_back(std::move(*s));  // world_from_scan: identity
  }
  ASSERT_EQ(scans.size(), 10u);
  RegisterOptions o;  // defaults
  o.root = "bun000";
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  std::vector<Eigen::Isometry3d> world;
  int registered = 0;
  for (const ScanRegistration& s : r->scans) {
    registered += s.registered;
    world.push_back(s.world_from_scan);
  }
  for (const io::LinkRecord& l : r->links) {
    if (l.status == io::LinkStatus::kFailed) continue;
    EXPECT_EQ(l.matches, 0) << "no reflectance: no SIFT matches expected";
    if (l.method.rfind("none+", 0) == 0) continue;  // refined from the registered poses for the global step
    EXPECT_GT(l.geometric_inliers, 0) << l.parent << " -> " << l.child;
  }
  // Every registered scan is right; an unregistered one counts against the floor below.
  double pos = 0, ang = 0;
  for (std::size_t i = 1; i < scans.size(); ++i) {
    if (!r->scans[i].registered) continue;
    const PoseError e = ComparePoses(world[0].inverse() * world[i], scans[0].reference_world_from_scan->inverse() *
                                                                        *scans[i].reference_world_from_scan);
    pos = std::max(pos, e.position_m);
    ang = std::max(ang, e.angle_rad);
  }
  std::printf("bunny from identity, defaults: %d / 10 registered, worst %.2f mm %.3f deg\n", registered, pos * 1e3,
              ang * kDeg);
  EXPECT_EQ(registered, 10);
  EXPECT_LT(pos, 0.002);
  EXPECT_LT(ang, 1.0 / kDeg);
}

TEST(RegisterFromCurrentPoses, StanfordBunnyPerturbedBackToBunConf) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::vector<Scan> scans = PerturbedBunny(data, 3.0, 3.0);
  ASSERT_EQ(scans.size(), 4u);
  std::vector<Eigen::Isometry3d> start;
  for (const Scan& s : scans) start.push_back(s.world_from_scan);
  const auto [start_pos, start_ang] = WorstError(scans, start);
  EXPECT_GT(start_pos, 0.003);
  EXPECT_GT(start_ang, 2.9 / kDeg);
  NullProgress progress;
  CancelToken cancel;
  for (bool global : {false, true}) {
    Expected<ProjectRegistration> r =
        RegisterScans(scans, {}, BunnyOptions(FineMethod::kEm, global), progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    std::vector<Eigen::Isometry3d> world;
    for (const ScanRegistration& s : r->scans) {
      EXPECT_TRUE(s.registered) << s.name << ": " << s.reason;
      world.push_back(s.world_from_scan);
    }
    int tree = 0, extra = 0;
    for (const io::LinkRecord& l : r->links) {
      if (l.status == io::LinkStatus::kFailed) continue;
      (l.loop_check ? extra : tree)++;
      EXPECT_EQ(l.method, "none+em");
    }
    const auto [pos, ang] = WorstError(scans, world);
    std::printf(
        "bunny --coarse none --fine em%s: %d tree + %d extra links, worst %.2f mm %.3f deg (start %.2f mm %.2f deg)\n",
        global ? " --global" : "", tree, extra, pos * 1e3, ang * kDeg, start_pos * 1e3, start_ang * kDeg);
    EXPECT_EQ(tree, 3);
    EXPECT_EQ(r->global_links.empty(), !global);
    if (global) {
      EXPECT_GT(extra, 0);
    }
    EXPECT_LT(pos, 0.002);
    EXPECT_LT(ang, 1.0 / kDeg);
  }
}

TEST(RegisterFromCurrentPoses, RejectsKeypointsAndReportsScansWithoutOverlap) {
  std::vector<Scan> scans(2, Scan("a", 5, 5));
  scans[1].name = "b";
  for (Scan& s : scans)
    for (int r = 0; r < 5; ++r)
      for (int c = 0; c < 5; ++c) s.Set(r, c, Eigen::Vector3f(0.1f * c, 0.1f * r, 1.0f), 1.0f);
  scans[1].world_from_scan.translation() = Eigen::Vector3d(100, 0, 0);
  RegisterOptions o;
  o.from_current_poses = true;
  o.fine = FineMethod::kKeypoints;
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> bad = RegisterScans(scans, {}, o, progress, cancel);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("use em, projective-icp or dense"), std::string::npos) << bad.error().message;
  o.fine = FineMethod::kDense;
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  int registered = 0;
  for (const ScanRegistration& s : r->scans) registered += s.registered;
  EXPECT_EQ(registered, 1);  // the root only: 100 m apart, nothing overlaps
  const ScanRegistration& left = r->scans[r->root == 0 ? 1 : 0];
  EXPECT_NE(left.reason.find("overlaps"), std::string::npos) << left.reason;
}

// A simulated street registered with the image-based coarse step and EM as the fine step: every
// scan within a centimetre of the reference (W: 9-32 mm after fine registration).
TEST(RegisterWithEm, SimulatedStreetReachesMillimetres) {
  SimulatedProjectOptions sim;
  sim.stations = 2;
  sim.scanner.cols = 1500;
  sim.scanner.rows = 375;
  sim.scanner.range_noise_m = 0.012;
  sim.seed = sim.scanner.seed = sim.scene.seed = 3;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(sim, progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  {
    const FineMethod fine = FineMethod::kEm;
    RegisterOptions o;
    o.fine = fine;
    Expected<ProjectRegistration> r = RegisterScans(*scans, {}, o, progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    const std::vector<ReferenceError> errors = ReferenceErrors(*r, *scans);
    double worst = 0, worst_ang = 0;
    for (std::size_t i = 0; i < scans->size(); ++i) {
      ASSERT_TRUE(r->scans[i].registered) << r->scans[i].name << ": " << r->scans[i].reason;
      worst = std::max(worst, errors[i].position_m);
      worst_ang = std::max(worst_ang, errors[i].angle_rad);
    }
    std::printf("street, 2 stations, --fine %s: worst %.1f mm %.4f deg\n", FineMethodName(fine), worst * 1e3,
                worst_ang * kDeg);
    EXPECT_LT(worst, 0.01);
    EXPECT_LT(worst_ang, 0.05 / kDeg);
    for (const io::LinkRecord& l : r->links) EXPECT_EQ(l.method.rfind("3d+em", 0), 0u) << l.method;
  }
}

}  // namespace
}  // namespace scanreg::pipeline
