// End-to-end registration of simulated projects with known poses (issue 3's acceptance tests).
#include "core/pipeline/register_project.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/geometry/transform.h"
#include "core/pipeline/project_edits.h"
#include "core/io/project_tree.h"
#include "core/simulate/project_sim.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

SimulatedProjectOptions StreetOptions(int stations, bool far_station = false) {
  SimulatedProjectOptions o;
  o.stations = stations;
  o.scanner.cols = 1500;
  o.scanner.rows = 375;
  o.scanner.range_noise_m = 0.012;
  o.seed = o.scanner.seed = o.scene.seed = 3;
  o.add_far_station = far_station;
  return o;
}

std::vector<Scan> Simulate(const SimulatedProjectOptions& o) {
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(scans.ok()) << scans.error().ToString();
  return scans.ok() ? std::move(*scans) : std::vector<Scan>{};
}

Expected<ProjectRegistration> Register(const std::vector<Scan>& scans, const RegisterOptions& options,
                                       std::vector<std::optional<std::string>> overrides = {}) {
  overrides.resize(scans.size());
  NullProgress progress;
  CancelToken cancel;
  return RegisterScans(scans, UserChoices{overrides, {}, {}}, options, progress, cancel);
}

class StreetProject : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { scans_ = new std::vector<Scan>(Simulate(StreetOptions(6))); }
  static void TearDownTestSuite() { delete scans_; }
  static std::vector<Scan>* scans_;
};
std::vector<Scan>* StreetProject::scans_ = nullptr;

TEST_F(StreetProject, EveryScanRegisteredWithinTwoCentimetresAndATenthOfADegree) {
  const std::vector<Scan>& scans = *scans_;
  ASSERT_EQ(scans.size(), 6u);
  Expected<ProjectRegistration> r = Register(scans, RegisterOptions{});
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const std::vector<ReferenceError> errors = ReferenceErrors(*r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    ASSERT_TRUE(r->scans[i].registered) << scans[i].name << ": " << r->scans[i].reason;
    ASSERT_TRUE(errors[i].available);
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name;
    EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << scans[i].name;
  }
  // The tree joins neighbouring stations (true distance below 2.5 station spacings).
  for (const ScanRegistration& s : r->scans) {
    if (s.parent < 0) continue;
    const Scan& child = scans[&s - r->scans.data()];
    const double d =
        (scans[s.parent].reference_world_from_scan->translation() - child.reference_world_from_scan->translation())
            .norm();
    EXPECT_LT(d, 12.5) << scans[s.parent].name << " <- " << child.name;
  }
  // The confusion matrix: diagonal = feature counts, neighbours share more matches than far scans.
  EXPECT_GT(r->confusion(0, 0), 500);
  EXPECT_GT(r->confusion(0, 1), r->confusion(0, 5));
  // Every tree link carries its evidence.
  int tree_links = 0;
  for (const io::LinkRecord& l : r->links) {
    if (l.status == io::LinkStatus::kFailed || l.loop_check) continue;
    ++tree_links;
    EXPECT_GE(l.consistent, 8);
    EXPECT_GT(l.overlap, 0.15) << l.parent << "-" << l.child;
    EXPECT_LT(l.rms_m, 0.03) << l.parent << "-" << l.child;
  }
  EXPECT_EQ(tree_links, 5);
}

TEST_F(StreetProject, GlobalRegistrationKeepsTheAccuracyAndReportsEveryLink) {
  const std::vector<Scan>& scans = *scans_;
  RegisterOptions options;
  options.global = options.verify_all_links = true;
  Expected<ProjectRegistration> r = Register(scans, options);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const std::vector<ReferenceError> errors = ReferenceErrors(*r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    ASSERT_TRUE(r->scans[i].registered) << scans[i].name;
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name;
  }
  int accepted = 0;
  for (const io::LinkRecord& l : r->links) accepted += l.status != io::LinkStatus::kFailed;
  ASSERT_EQ(static_cast<int>(r->global_links.size()), accepted);
  for (const auto& g : r->global_links) {
    EXPECT_FALSE(g.down_weighted) << g.parent << "-" << g.child << ": no wrong link in this project";
    EXPECT_LT(g.translation_after_m, 0.02) << g.parent << "-" << g.child;
  }
}

// Issue 14: Register all keeps the user's decisions — a hand placement stays where the user put it
// (scans registered through it rest on it and are marked so), an accepted link stays accepted.
TEST_F(StreetProject, RegisterAllKeepsAHandPlacementAndMarksTheScansThatRestOnIt) {
  std::vector<Scan> scans = *scans_;
  io::Project project;
  for (Scan& s : scans) {
    s.world_from_scan = s.name == "s01" ? *s.reference_world_from_scan : Eigen::Isometry3d::Identity();
    io::ProjectScan ps;
    ps.name = s.name;
    ps.world_from_scan = s.world_from_scan;
    project.scans.push_back(ps);
  }
  project.root = "s01";
  // s03 placed by hand, 0.4 m and 3 degrees off the truth.
  const int hand = 2;
  const Eigen::Isometry3d placed = *scans[hand].reference_world_from_scan *
                                   Eigen::Translation3d(0.4, 0.0, 0.0) *
                                   Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(SetScanPose("s03", placed, false, project).ok());
  scans[hand].world_from_scan = placed;
  project.scans[3].parent_override = "s03";  // s04 registered through the hand-placed scan
  io::LinkRecord accepted;
  accepted.parent = "s04", accepted.child = "s05", accepted.user_accepted = true;
  project.links.push_back(accepted);
  NullProgress progress;
  Expected<ProjectRegistration> r = RegisterProjectScans(project, scans, RegisterOptions(), progress, CancelToken());
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const io::ProjectScan& s03 = project.scans[hand];
  EXPECT_TRUE(s03.registered && s03.manual_pose);
  EXPECT_TRUE(s03.world_from_scan.isApprox(placed, 1e-12)) << "the hand placement was moved";
  const std::vector<bool> rests = io::RestsOnHandPlacement(project);
  EXPECT_TRUE(rests[hand]);
  EXPECT_TRUE(rests[3]) << "s04 hangs off s03";
  int resting = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    ASSERT_TRUE(project.scans[i].registered) << scans[i].name << ": " << project.scans[i].unregistered_reason;
    const PoseError e = ComparePoses(project.scans[i].world_from_scan, *scans[i].reference_world_from_scan);
    if (rests[i]) {
      ++resting;
      EXPECT_GT(e.position_m, 0.1) << scans[i].name << " rests on the hand placement and carries its offset";
    } else {
      EXPECT_LT(e.position_m, 0.02) << scans[i].name;
    }
  }
  EXPECT_LT(resting, static_cast<int>(scans.size()));  // the root does not rest on s03
  bool still_accepted = false;
  for (const io::LinkRecord& l : project.links)
    still_accepted |= l.parent == "s04" && l.child == "s05" && l.user_accepted;
  EXPECT_TRUE(still_accepted);

  // Released, the scan is placed by the registration again, within 2 cm of the truth.
  ASSERT_TRUE(ReleaseHandPlacement("s03", project).ok());
  EXPECT_FALSE(ReleaseHandPlacement("s03", project).ok());
  Expected<ProjectRegistration> again =
      RegisterProjectScans(project, scans, RegisterOptions(), progress, CancelToken());
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(project.scans[hand].manual_pose);
  EXPECT_LT(ComparePoses(project.scans[hand].world_from_scan, *scans[hand].reference_world_from_scan).position_m, 0.02);
}

TEST(RegisterProjectTest, ParentOverrideChangesTheChain) {
  SimulatedProjectOptions o = StreetOptions(4);
  o.spacing_m = 3.0;  // close stations, so that a scan two stations away is a registrable parent
  const std::vector<Scan> scans = Simulate(o);
  RegisterOptions options;
  options.root = "s01";
  Expected<ProjectRegistration> automatic = Register(scans, options);
  ASSERT_TRUE(automatic.ok());
  // Ask for s04 to hang off s02 — a choice the automatic tree did not make.
  const int s02 = 1, s04 = 3;
  ASSERT_NE(automatic->scans[s04].parent, s02) << "pick another pair for this test";
  std::vector<std::optional<std::string>> overrides(scans.size());
  overrides[s04] = "s02";
  Expected<ProjectRegistration> manual = Register(scans, options, overrides);
  ASSERT_TRUE(manual.ok()) << manual.error().ToString();
  EXPECT_EQ(manual->scans[s04].parent, s02);
  ASSERT_TRUE(manual->scans[s04].registered) << manual->scans[s04].reason;
  const std::vector<ReferenceError> errors = ReferenceErrors(*manual, scans);
  EXPECT_LE(errors[s04].position_m, 0.03);
}

TEST(RegisterProjectTest, FarStationIsReportedUnregisteredAndTheOthersSucceed) {
  const std::vector<Scan> scans = Simulate(StreetOptions(4, /*far_station=*/true));
  ASSERT_EQ(scans.size(), 5u);
  Expected<ProjectRegistration> r = Register(scans, RegisterOptions{});
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const std::vector<ReferenceError> errors = ReferenceErrors(*r, scans);
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(r->scans[i].registered) << scans[i].name << ": " << r->scans[i].reason;
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name;
  }
  EXPECT_FALSE(r->scans[4].registered);
  EXPECT_FALSE(r->scans[4].reason.empty());
  EXPECT_NE(r->root, 4);
}

TEST(RegisterProjectTest, RepeatedWindowsNeverYieldAWrongAcceptedLink) {
  SimulatedProjectOptions o = StreetOptions(5);
  o.scene.kind = SceneOptions::Kind::kRepeatedWindows;
  const std::vector<Scan> scans = Simulate(o);
  for (CoarseMethod method : {CoarseMethod::kEpnp, CoarseMethod::k3d}) {
    RegisterOptions options;
    options.coarse.method = method;
    Expected<ProjectRegistration> r = Register(scans, options);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    for (const io::LinkRecord& l : r->links) {
      if (l.status == io::LinkStatus::kFailed) {
        EXPECT_FALSE(l.reason.empty());
        continue;
      }
      const PoseError e = *LinkReferenceError(l, scans);
      EXPECT_LT(e.position_m, 0.10) << l.parent << " <- " << l.child << " accepted with a wrong pose";
      EXPECT_LT(e.angle_rad * kDeg, 0.5) << l.parent << " <- " << l.child;
    }
  }
}

// Two scans alone, 5 m apart on a static street at 1000x250: few correspondences agree (fewer than
// the 15 that make a link well supported), and no third scan can close a loop. The surfaces carry
// the pose — most of the child overlaps at the noise level and nothing lies in the other scanner's
// free space — so the pair is registered, with that evidence named, not left "not verified".
TEST(RegisterProjectTest, AnIsolatedPairWithFewCorrespondencesIsRegisteredWhenTheSurfacesAgree) {
  SimulatedProjectOptions o = StreetOptions(2);
  o.scanner.cols = 1000;
  o.scanner.rows = 250;
  o.seed = o.scanner.seed = o.scene.seed = 1;
  const std::vector<Scan> scans = Simulate(o);
  ASSERT_EQ(scans.size(), 2u);
  Expected<ProjectRegistration> r = Register(scans, RegisterOptions{});
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  ASSERT_EQ(r->links.size(), 1u);
  const io::LinkRecord& link = r->links[0];
  ASSERT_LT(link.consistent, RegisterOptions{}.thresholds.weak_inliers) << "the pair no longer tests the weak case";
  ASSERT_TRUE(r->scans[0].registered && r->scans[1].registered)
      << r->scans[0].reason << " / " << r->scans[1].reason << " / " << link.reason;
  EXPECT_NE(link.reason.find("the surfaces agree"), std::string::npos) << link.reason;
  const PoseError e = *LinkReferenceError(link, scans);
  EXPECT_LT(e.position_m, 0.02);
  EXPECT_LT(e.angle_rad * kDeg, 0.1);
}

TEST(RegisterProjectTest, NonsenseOptionsAndTooFewScansAreErrors) {
  RegisterOptions bad;
  bad.match.ratio = 0.0;
  const std::vector<Scan> one(1, Scan("a", 4, 4));
  EXPECT_EQ(Register(one, RegisterOptions{}).error().code, ErrorCode::kInvalidArgument);
  std::vector<Scan> two = {Scan("a", 4, 4), Scan("b", 4, 4)};
  Expected<ProjectRegistration> r = Register(two, RegisterOptions{});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'a'"), std::string::npos) << "an empty scan is named";
  EXPECT_FALSE(Register(two, bad).ok());
}

// A cycle of parent overrides is named by scan names, before any feature is computed.
TEST(RegisterProjectTest, OverrideCycleIsNamedBeforeTheFeatures) {
  SimulatedProjectOptions o = StreetOptions(3);
  o.scanner.cols = 300;
  o.scanner.rows = 80;
  const std::vector<Scan> scans = Simulate(o);
  ASSERT_EQ(scans.size(), 3u);
  test::TempDir cache;
  RegisterOptions options;
  options.feature_cache_dir = cache.path();
  Expected<ProjectRegistration> r =
      Register(scans, options, {std::string("s02"), std::string("s03"), std::string("s01")});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("s01 -> s02 -> s03 -> s01"), std::string::npos) << r.error().message;
  EXPECT_TRUE(std::filesystem::is_empty(cache.path())) << "no feature was computed";
}

}  // namespace
}  // namespace scanreg::pipeline
