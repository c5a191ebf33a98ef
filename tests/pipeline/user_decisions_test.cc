// Issue 14: what the user decides is kept — a link from picked points, an accepted link, the scans
// already registered when only the missing ones are placed, and the old link when a forced one
// fails. Simulated street projects with known poses.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/project_tree.h"
#include "core/pipeline/manual_alignment.h"
#include "core/pipeline/project_edits.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/scan_store.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d RandomPose(std::mt19937& rng, bool levelled) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d axis = levelled ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
  t.linear() = Eigen::AngleAxisd(3.0 * u(rng), axis).toRotationMatrix();
  t.translation() = Eigen::Vector3d(10 * u(rng), 10 * u(rng), levelled ? 0.5 * u(rng) : 10 * u(rng));
  return t;
}

std::vector<io::PickedPoint> PicksFor(const Eigen::Isometry3d& parent_from_child, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-8.0, 8.0);
  std::vector<io::PickedPoint> picks;
  for (int i = 0; i < count; ++i) {
    io::PickedPoint p;
    p.child = Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng));
    p.parent = parent_from_child * p.child;
    picks.push_back(p);
  }
  return picks;
}

TEST(ManualAlignment, FitIsExactOnPerfectPicksAndLevelledScansNeedTwo) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d truth = RandomPose(rng, false);
    Expected<PickedFit> fit = FitPickedPoints(PicksFor(truth, 4, rng), false);
    ASSERT_TRUE(fit.ok()) << fit.error().ToString();
    EXPECT_TRUE(fit->parent_from_child.isApprox(truth, 1e-9));
    EXPECT_LT(fit->rms_m, 1e-9);
    EXPECT_EQ(fit->residual_m.size(), 4u);

    const Eigen::Isometry3d level = RandomPose(rng, true);
    Expected<PickedFit> two = FitPickedPoints(PicksFor(level, 2, rng), true);
    ASSERT_TRUE(two.ok()) << two.error().ToString();
    EXPECT_TRUE(two->parent_from_child.isApprox(level, 1e-9));
    EXPECT_TRUE(two->levelled);
  }
}

TEST(ManualAlignment, TooFewCollinearOrNonFinitePicksAreNamed) {
  std::mt19937 rng(6);
  const Eigen::Isometry3d truth = RandomPose(rng, false);
  Expected<PickedFit> two = FitPickedPoints(PicksFor(truth, 2, rng), false);
  ASSERT_FALSE(two.ok());
  EXPECT_NE(two.error().message.find("at least 3"), std::string::npos) << two.error().message;
  std::vector<io::PickedPoint> line;
  for (int i = 0; i < 4; ++i) line.push_back({Eigen::Vector3d(i, 2 * i, 0), truth * Eigen::Vector3d(i, 2 * i, 0)});
  Expected<PickedFit> collinear = FitPickedPoints(line, false);
  ASSERT_FALSE(collinear.ok());
  EXPECT_NE(collinear.error().message.find("one line"), std::string::npos) << collinear.error().message;
  std::vector<io::PickedPoint> nan = PicksFor(truth, 3, rng);
  nan[1].parent.x() = NAN;
  Expected<PickedFit> bad = FitPickedPoints(nan, false);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("pair 2"), std::string::npos) << bad.error().message;
}

SimulatedProjectOptions Street(int stations, double spacing_m) {
  SimulatedProjectOptions o;
  o.stations = stations;
  o.spacing_m = spacing_m;
  o.scanner.cols = 1500;
  o.scanner.rows = 375;
  o.scanner.range_noise_m = 0.012;
  o.seed = o.scanner.seed = o.scene.seed = 3;
  return o;
}

std::vector<Scan> Simulate(const SimulatedProjectOptions& o) {
  NullProgress progress;
  Expected<std::vector<Scan>> scans = SimulateProject(o, progress, CancelToken());
  EXPECT_TRUE(scans.ok()) << scans.error().ToString();
  return scans.ok() ? std::move(*scans) : std::vector<Scan>{};
}

io::Project ProjectOf(const std::vector<Scan>& scans) {
  io::Project project;
  for (const Scan& s : scans) {
    io::ProjectScan ps;
    ps.name = s.name;
    ps.world_from_scan = s.world_from_scan;
    project.scans.push_back(ps);
  }
  return project;
}

// The points a user would pick: cells of the child, spread over its panorama, that the parent saw
// too (its nearest point within 3 cm at the true poses), each paired with that nearest parent point
// and moved by up to `click_m` (a click is not exact).
std::vector<io::PickedPoint> PickLikeAUser(const Scan& parent, const Scan& child, int count, double click_m) {
  const Eigen::Isometry3d parent_from_child =
      parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-click_m, click_m);
  std::vector<io::PickedPoint> picks;
  for (int k = 0; k < 8 * count && static_cast<int>(picks.size()) < count; ++k) {
    const int col = (k * child.cols / (2 * count) + child.cols / 7) % child.cols;
    const int row = child.rows / 3 + (k % 3) * child.rows / 8;
    if (!child.IsValid(row, col)) continue;
    const Eigen::Vector3d c = child.Point(row, col).cast<double>();
    if (c.norm() > 20.0) continue;
    const Eigen::Vector3d in_parent = parent_from_child * c;
    double best = INFINITY;
    Eigen::Vector3d nearest;
    for (std::size_t i = 0; i < parent.size(); ++i) {
      if (!parent.valid[i]) continue;
      const double d = (parent.points[i].cast<double>() - in_parent).squaredNorm();
      if (d < best) best = d, nearest = parent.points[i].cast<double>();
    }
    if (std::sqrt(best) > 0.03) continue;  // hidden from the parent
    picks.push_back({nearest + Eigen::Vector3d(u(rng), u(rng), u(rng)), c});
  }
  return picks;
}

class UserDecisions : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scans_ = new std::vector<Scan>(Simulate(Street(4, 6.0)));
    NullProgress progress;
    registered_ = new io::Project(ProjectOf(*scans_));
    registered_->root = "s01";
    Expected<ProjectRegistration> r = RegisterProjectScans(*registered_, *scans_, RegisterOptions(), progress, CancelToken());
    ASSERT_TRUE(r.ok()) << r.error().ToString();
  }
  static void TearDownTestSuite() {
    delete scans_;
    delete registered_;
  }
  // The scans at the registered project's poses.
  static std::vector<Scan> ScansAt(const io::Project& project) {
    std::vector<Scan> scans = *scans_;
    for (std::size_t i = 0; i < scans.size(); ++i) scans[i].world_from_scan = project.scans[i].world_from_scan;
    return scans;
  }
  static PoseError ErrorOf(const io::Project& project, int i) {
    const Eigen::Isometry3d root = *(*scans_)[0].reference_world_from_scan;
    return ComparePoses(project.scans[0].world_from_scan.inverse() * project.scans[i].world_from_scan,
                        root.inverse() * *(*scans_)[i].reference_world_from_scan);
  }
  static std::vector<Scan>* scans_;
  static io::Project* registered_;
};
std::vector<Scan>* UserDecisions::scans_ = nullptr;
io::Project* UserDecisions::registered_ = nullptr;

TEST_F(UserDecisions, TheAutomaticRegistrationPlacesEveryScan) {
  for (std::size_t i = 0; i < scans_->size(); ++i) {
    ASSERT_TRUE(registered_->scans[i].registered) << registered_->scans[i].unregistered_reason;
    EXPECT_LT(ErrorOf(*registered_, i).position_m, 0.02);
  }
}

// Picked points with clicks up to 5 cm off, from a child 2 m and 10 degrees away from where it
// belongs: the link from picked points lands within 2 cm / 0.1 degree after refinement.
TEST_F(UserDecisions, PickedPointsAlignAPairWithinTwoCentimetres) {
  const Scan& parent = (*scans_)[1];
  const Scan& child = (*scans_)[2];
  const std::vector<io::PickedPoint> picks = PickLikeAUser(parent, child, 4, 0.05);
  ASSERT_EQ(picks.size(), 4u);
  Expected<io::LinkRecord> link = AlignFromPickedPoints(parent, child, picks, false, RegisterOptions(), CancelToken());
  ASSERT_TRUE(link.ok()) << link.error().ToString();
  EXPECT_NE(link->status, io::LinkStatus::kFailed) << link->reason;
  EXPECT_EQ(link->method.rfind("picked+", 0), 0u) << link->method;
  EXPECT_EQ(link->picked.size(), 4u);
  const Eigen::Isometry3d truth = parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan;
  const PoseError e = ComparePoses(link->parent_from_child, truth);
  EXPECT_LT(e.position_m, 0.02);
  EXPECT_LT(e.angle_rad, 0.1 * kDeg);
  // The picked fit alone is farther off: the refinement did the work.
  Expected<PickedFit> fit = FitPickedPoints(picks, false);
  ASSERT_TRUE(fit.ok());
  EXPECT_GT(ComparePoses(fit->parent_from_child, truth).position_m, e.position_m);

  // Two picks suffice for levelled scans (the simulated stations tilt by at most half a degree).
  const std::vector<io::PickedPoint> two(picks.begin(), picks.begin() + 2);
  Expected<io::LinkRecord> levelled = AlignFromPickedPoints(parent, child, two, true, RegisterOptions(), CancelToken());
  ASSERT_TRUE(levelled.ok()) << levelled.error().ToString();
  EXPECT_LT(ComparePoses(levelled->parent_from_child, truth).position_m, 0.02) << levelled->reason;

  // A pick on the wrong point is named, not refined into a wrong link.
  std::vector<io::PickedPoint> wrong = picks;
  wrong[2].parent += Eigen::Vector3d(4.0, -3.0, 0.0);
  Expected<io::LinkRecord> refused = AlignFromPickedPoints(parent, child, wrong, false, RegisterOptions(), CancelToken());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("picked pair"), std::string::npos) << refused.error().message;
}

// A link from picked points is the user's: Register all uses it as it is (its pose, its picks) and
// places the child from it.
TEST_F(UserDecisions, RegisterAllKeepsALinkFromPickedPoints) {
  io::Project project = *registered_;
  const Scan& parent = (*scans_)[1];
  const Scan& child = (*scans_)[2];
  Expected<io::LinkRecord> link =
      AlignFromPickedPoints(parent, child, PickLikeAUser(parent, child, 4, 0.05), false, RegisterOptions(), CancelToken());
  ASSERT_TRUE(link.ok()) << link.error().ToString();
  // Offset it by 1 cm so that a recomputed link could not pass for it.
  link->parent_from_child = link->parent_from_child * Eigen::Translation3d(0.01, 0, 0);
  ASSERT_TRUE(ApplyPairResult(*link, project).ok());
  NullProgress progress;
  Expected<ProjectRegistration> r = RegisterProjectScans(project, ScansAt(project), RegisterOptions(), progress, CancelToken());
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const io::LinkRecord* kept = nullptr;
  for (const io::LinkRecord& l : project.links)
    if (io::IsTreeLink(l) && l.child == "s03") kept = &l;
  ASSERT_NE(kept, nullptr);
  EXPECT_EQ(kept->parent, "s02");
  EXPECT_TRUE(kept->parent_from_child.isApprox(link->parent_from_child, 1e-12));
  EXPECT_EQ(kept->picked.size(), 4u);
  EXPECT_TRUE(kept->user_accepted);
  const Eigen::Isometry3d expected = project.scans[1].world_from_scan * link->parent_from_child;
  EXPECT_TRUE(project.scans[2].world_from_scan.isApprox(expected, 1e-9));
}

// Register unregistered scans: the registered ones keep their poses to the bit and their links; the
// missing one is placed within 2 cm.
TEST_F(UserDecisions, OnlyTheUnregisteredScansArePlaced) {
  io::Project project = *registered_;
  project.scans[3].registered = false;
  project.scans[3].world_from_scan = Eigen::Isometry3d::Identity();
  project.links.erase(std::remove_if(project.links.begin(), project.links.end(),
                                     [](const io::LinkRecord& l) { return l.child == "s04"; }),
                      project.links.end());
  // Shift the registered scans by a known datum: a full re-run would put them back.
  const Eigen::Isometry3d datum(Eigen::Translation3d(100, 200, 3));
  for (int i = 0; i < 3; ++i) project.scans[i].world_from_scan = datum * project.scans[i].world_from_scan;
  const io::Project before = project;
  RegisterOptions options;
  options.only_scans = {"s04"};
  NullProgress progress;
  Expected<ProjectRegistration> r = RegisterProjectScans(project, ScansAt(project), options, progress, CancelToken());
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  for (int i = 0; i < 3; ++i)
    EXPECT_TRUE(project.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0)) << i;
  ASSERT_TRUE(project.scans[3].registered) << project.scans[3].unregistered_reason;
  EXPECT_LT(ErrorOf(project, 3).position_m, 0.02);
  EXPECT_LT(ErrorOf(project, 3).angle_rad, 0.1 * kDeg);
  for (const io::LinkRecord& old : before.links) {
    bool same = false;
    for (const io::LinkRecord& l : project.links)
      same |= l.parent == old.parent && l.child == old.child && l.parent_from_child.isApprox(old.parent_from_child, 0.0);
    EXPECT_TRUE(same) << old.child << " -> " << old.parent << " was recomputed or dropped";
  }
}

// A parent override whose link fails leaves the old link and pose; one that works re-registers only
// the scan and the scans under it.
TEST_F(UserDecisions, AFailingOverrideKeepsTheOldLinkAndAWorkingOneMovesOnlyTheSubtree) {
  io::Project project = *registered_;
  const std::vector<Scan> at = ScansAt(project);
  ScanStore scans(at);
  const io::Project before = project;
  NullProgress progress;
  // Evidence no pair of these stations can give (95 % overlap): the forced link s04 -> s02 fails.
  RegisterOptions strict;
  strict.thresholds.min_overlap = 0.95;
  strict.thresholds.weak_overlap = 0.97;
  Expected<OverrideOutcome> failed =
      OverrideParent(project, scans, "s04", std::string("s02"), strict, progress, CancelToken());
  ASSERT_TRUE(failed.ok()) << failed.error().ToString();
  EXPECT_FALSE(failed->applied);
  EXPECT_NE(failed->message.find("keeps its link to s03"), std::string::npos) << failed->message;
  EXPECT_FALSE(project.scans[3].parent_override.has_value());
  EXPECT_TRUE(project.scans[3].registered);
  EXPECT_TRUE(project.scans[3].world_from_scan.isApprox(before.scans[3].world_from_scan, 0.0));

  // s04 to s02 (6 m spacing: 12 m apart) — the scans not under s04 do not move.
  Expected<OverrideOutcome> moved =
      OverrideParent(project, scans, "s04", std::string("s02"), RegisterOptions(), progress, CancelToken());
  ASSERT_TRUE(moved.ok()) << moved.error().ToString();
  ASSERT_TRUE(moved->applied) << moved->message;
  EXPECT_EQ(project.scans[3].parent_override.value_or(""), "s02");
  for (int i : {0, 1, 2})
    EXPECT_TRUE(project.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0)) << i;
  EXPECT_LT(ErrorOf(project, 3).position_m, 0.02) << moved->message;
  EXPECT_FALSE(OverrideParent(project, scans, "s01", std::string("s02"), RegisterOptions(), progress, CancelToken()).ok())
      << "the root has no parent";
}

// Scans that register to each other but not to the root form a cluster (kept in its own frame, shown
// as such); one link from a registered scan to any scan of it places the whole cluster.
TEST(Clusters, AGroupThatDoesNotReachTheRootIsKeptTogetherAndJoinedByOneLink) {
  SimulatedProjectOptions a = Street(2, 5.0), b = Street(2, 5.0);
  // The registered pair at 1500 x 375: at 1000 x 250 its link has 11 consistent correspondences,
  // too few to be verified without a loop (a pair has none), and s02 would be left unregistered.
  a.scanner.cols = 1500;
  a.scanner.rows = 375;
  b.scanner.cols = 1000;
  b.scanner.rows = 250;
  b.seed = b.scene.seed = 99;  // another street: nothing in common with the first
  std::vector<Scan> scans = Simulate(a);
  for (Scan& s : Simulate(b)) {
    s.name = "t" + s.name.substr(1);
    scans.push_back(std::move(s));
  }
  ASSERT_EQ(scans.size(), 4u);
  io::Project project = ProjectOf(scans);
  project.root = "s01";
  NullProgress progress;
  Expected<ProjectRegistration> r = RegisterProjectScans(project, scans, RegisterOptions(), progress, CancelToken());
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  EXPECT_TRUE(project.scans[1].registered) << project.scans[1].unregistered_reason;
  ASSERT_FALSE(project.scans[2].registered);
  ASSERT_FALSE(project.scans[3].registered);
  const std::string cluster = project.scans[2].cluster;
  ASSERT_FALSE(cluster.empty()) << project.scans[2].unregistered_reason;
  EXPECT_EQ(project.scans[3].cluster, cluster);
  EXPECT_TRUE(project.scans[0].cluster.empty());
  // Within the cluster the relative pose is registered: t02 from t01 within 2 cm / 0.1 degree.
  const auto relative = [&](const io::Project& p) {
    return ComparePoses(p.scans[2].world_from_scan.inverse() * p.scans[3].world_from_scan,
                        scans[2].reference_world_from_scan->inverse() * *scans[3].reference_world_from_scan);
  };
  EXPECT_LT(relative(project).position_m, 0.02);
  EXPECT_LT(relative(project).angle_rad, 0.1 * kDeg);
  // Saved and read back, the cluster is still there.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "scanreg_clusters_test.scanreg.json";
  for (io::ProjectScan& s : project.scans) s.path = file;  // any existing file: only the project is read
  ASSERT_TRUE(io::SaveProject(project, file).ok());
  Expected<io::Project> back = io::LoadProject(file);
  std::filesystem::remove(file);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->scans[3].cluster, cluster);

  // One link, s02 -> t02 (any pose: the streets are unrelated), places both t01 and t02.
  io::LinkRecord join;
  join.parent = "s02";
  join.child = "t02";
  join.status = io::LinkStatus::kOk;
  join.method = "picked+dense";
  join.parent_from_child = Eigen::Translation3d(30, 5, 0) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ());
  ASSERT_TRUE(ApplyPairResult(join, project).ok());
  for (int i : {2, 3}) {
    EXPECT_TRUE(project.scans[i].registered);
    EXPECT_TRUE(project.scans[i].cluster.empty());
  }
  EXPECT_TRUE(project.scans[3].world_from_scan.isApprox(project.scans[1].world_from_scan * join.parent_from_child, 1e-9));
  EXPECT_LT(relative(project).position_m, 0.02) << "the cluster moved as one";
  // Every scan but the root has exactly one tree link, and following them reaches the root.
  for (std::size_t i = 1; i < project.scans.size(); ++i) {
    int into = 0;
    for (const io::LinkRecord& l : project.links) into += io::IsTreeLink(l) && l.child == project.scans[i].name;
    EXPECT_EQ(into, 1) << project.scans[i].name;
  }
  const std::vector<int> reached = io::ScansRegisteredThrough(project, 0);
  EXPECT_EQ(reached.size(), 4u);
}

}  // namespace
}  // namespace scanreg::pipeline
