// Issue 11: projects outside the paper's conditions, with known poses. Sparse stations (10 and 15
// m), low resolution (600x150) and no usable reflectance must register every scan within 2 cm /
// 0.1° with default options, and no accepted link may be wrong; SIFT alone (the paper's method)
// must fail where the geometric sources do the work, or the test would prove nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <unordered_set>

#include "core/geometry/transform.h"
#include "core/io/scan_file.h"
#include "core/pipeline/register_project.h"
#include "core/registration/plan_view.h"
#include "core/simulate/project_sim.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

struct Hard {
  int stations, cols, rows;
  double spacing;
  bool reflectance;
  std::uint64_t seed;
  int traffic = 0;  // moving vehicles per scan (and twice as many pedestrians), new in every scan
  double tilt_deg = 0.5;
};

std::vector<Scan> Simulate(const Hard& h) {
  SimulatedProjectOptions o;
  o.stations = h.stations;
  o.spacing_m = h.spacing;
  o.scanner.cols = h.cols;
  o.scanner.rows = h.rows;
  o.scanner.reflectance = h.reflectance;
  o.max_tilt_deg = h.tilt_deg;
  if (h.traffic > 0) {  // and the noise of a real street scan: angles, range noise growing with range
    o.traffic.vehicles = h.traffic;
    o.traffic.pedestrians = 2 * h.traffic;
    o.scanner.angle_noise_deg = 0.005;
    o.scanner.range_noise_per_m = 1e-4;
  }
  o.seed = o.scanner.seed = o.scene.seed = h.seed;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(scans.ok()) << scans.error().ToString();
  return scans.ok() ? std::move(*scans) : std::vector<Scan>{};
}

ProjectRegistration Register(const std::vector<Scan>& scans, const RegisterOptions& options) {
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> r = RegisterScans(scans, {},
                                                  options, progress, cancel);
  EXPECT_TRUE(r.ok()) << r.error().ToString();
  return r.ok() ? *r : ProjectRegistration{};
}

int CountRegistered(const ProjectRegistration& r) {
  int n = 0;
  for (const ScanRegistration& s : r.scans) n += s.registered;
  return n;
}

// Every scan within 2 cm / 0.1°, and every accepted (ok or weak) link within 5 cm / 0.2° of the truth.
void ExpectAllRegisteredAndNoWrongLink(const std::vector<Scan>& scans, const ProjectRegistration& r) {
  ASSERT_EQ(r.scans.size(), scans.size());
  const std::vector<ReferenceError> errors = ReferenceErrors(r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    EXPECT_TRUE(r.scans[i].registered) << scans[i].name << ": " << r.scans[i].reason;
    if (!r.scans[i].registered) continue;
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name;
    EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << scans[i].name;
  }
  int accepted = 0;
  for (const io::LinkRecord& l : r.links) {
    if (l.status == io::LinkStatus::kFailed) continue;
    ++accepted;
    const PoseError e = *LinkReferenceError(l, scans);
    EXPECT_LE(e.position_m, 0.05) << l.parent << "-" << l.child << " accepted but wrong (" << l.method << ")";
    EXPECT_LE(e.angle_rad * kDeg, 0.2) << l.parent << "-" << l.child;
  }
  EXPECT_GE(accepted, static_cast<int>(scans.size()) - 1);
}

TEST(HardProjects, StationsTenMetresApart) {
  const std::vector<Scan> scans = Simulate({5, 1000, 250, 10.0, true, 3});
  const ProjectRegistration r = Register(scans, RegisterOptions{});
  ExpectAllRegisteredAndNoWrongLink(scans, r);
  // The paper's SIFT-only pipeline does not manage it (the reason this issue exists).
  RegisterOptions sift_only;
  sift_only.features = FeatureSources::kSift;
  EXPECT_LT(CountRegistered(Register(scans, sift_only)), static_cast<int>(scans.size()));
}

TEST(HardProjects, StationsFifteenMetresApart) {
  const std::vector<Scan> scans = Simulate({4, 1500, 375, 15.0, true, 4});
  ExpectAllRegisteredAndNoWrongLink(scans, Register(scans, RegisterOptions{}));
}

// Cars, vans, a bus and people placed anew in every scan: their points lie in the other scanners'
// free space at the true poses (about 10 % of the samples here); the links stay ok and report them.
TEST(HardProjects, StreetWithTraffic) {
  const std::vector<Scan> scans = Simulate({6, 1000, 250, 5.0, true, 8, 8});
  const ProjectRegistration r = Register(scans, RegisterOptions{});
  ExpectAllRegisteredAndNoWrongLink(scans, r);
  double most_moving = 0.0;
  for (const io::LinkRecord& l : r.links)
    if (l.status != io::LinkStatus::kFailed) most_moving = std::max(most_moving, l.moving);
  EXPECT_GT(most_moving, 0.02) << "the traffic is reported on the links";
}

// Issue 37: the hard conditions together. A busy street 12 m apart: 6 vehicles and 12 pedestrians
// anew in every scan, angle noise, range noise growing with range. Fine FPFH (0.17 m here) and SIFT
// find almost no agreeing correspondences between stations this far apart, and the plan-view poses
// alone leave weak links beside the traffic (5 of 6 scans by default); FPFH at a coarse scale (3
// voxels, 0.5 m: --coarse-scale 3) gives tens.
RegisterOptions CoarseScale() {
  RegisterOptions o;
  o.geometric.coarse_scale = 3.0;
  return o;
}

// The tree links (each registered scan's link to its parent) that rest on at least 10 agreeing
// correspondences rather than on the plan view alone.
int TreeLinksByCorrespondences(const std::vector<Scan>& scans, const ProjectRegistration& r) {
  int n = 0;
  for (const ScanRegistration& s : r.scans) {
    if (!s.registered || s.parent < 0) continue;
    for (const io::LinkRecord& l : r.links)
      n += l.parent == scans[s.parent].name && l.child == s.name && l.status != io::LinkStatus::kFailed &&
           l.consistent >= 10;
  }
  return n;
}

TEST(HardProjects, BusyStreetTwelveMetresApartWithCoarseFeatures) {
  const std::vector<Scan> scans = Simulate({6, 1000, 250, 12.0, true, 3, 6});
  const ProjectRegistration coarse = Register(scans, CoarseScale());
  ExpectAllRegisteredAndNoWrongLink(scans, coarse);
  EXPECT_GE(TreeLinksByCorrespondences(scans, coarse), 4) << "of 5: the coarse scale's correspondences place them";
  // By default the same scans are placed by the plan view (issue 37: all 6 since three agreeing
  // plan-view poses confirm a scan), not by correspondences: else the test would prove nothing.
  EXPECT_LE(TreeLinksByCorrespondences(scans, Register(scans, RegisterOptions{})), 1)
      << "the fine scale alone finds the correspondences: the test would prove nothing";
}

// The same busy street with default options (issue 37): the plan view maps every wall each scanner
// saw — far façades too, which the feature samples leave out — so the true poses are its peaks
// and the surfaces confirm them (2 of 6 scans registered on both seeds before, all turned or
// same-spot poses; 5 and 6 now). Weak links that no loop confirms may leave a scan out, never
// placed wrong.
// With default options: at least `min_registered` scans, each within 2 cm / 0.1°, and no accepted
// link wrong; scans left out are allowed (weak links no loop confirms), never placed wrong.
void ExpectMostRegisteredAndNoWrongLink(const Hard& h, int min_registered) {
  const std::vector<Scan> scans = Simulate(h);
  const ProjectRegistration r = Register(scans, RegisterOptions{});
  ASSERT_EQ(r.scans.size(), scans.size());
  const std::vector<ReferenceError> errors = ReferenceErrors(r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!r.scans[i].registered) continue;
    EXPECT_LE(errors[i].position_m, 0.02) << "seed " << h.seed << " " << scans[i].name;
    EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << "seed " << h.seed << " " << scans[i].name;
  }
  EXPECT_GE(CountRegistered(r), min_registered) << "seed " << h.seed;
  for (const io::LinkRecord& l : r.links) {
    if (l.status == io::LinkStatus::kFailed) continue;
    const PoseError e = *LinkReferenceError(l, scans);
    EXPECT_LE(e.position_m, 0.05) << "seed " << h.seed << " " << l.parent << "-" << l.child << " accepted but wrong";
    EXPECT_LE(e.angle_rad * kDeg, 0.2) << "seed " << h.seed << " " << l.parent << "-" << l.child;
  }
}

// Seed 7: the plan-view links between three stations and the rest all fit to 2 mm and carry 2-9 %
// traffic in each other's free space; while object-sized conflicts made a plan-view pose need a
// loop, and the one link between the two groups had none, 3 of 6 were registered. Conflicts that
// stand out of the other scan's range image are traffic (visibility.h): every scan, none wrong.
TEST(HardProjects, BusyStreetTwelveMetresApartByThePlanView) {
  for (const std::uint64_t seed : {3u, 5u, 7u}) ExpectMostRegisteredAndNoWrongLink({6, 1000, 250, 12.0, true, seed, 6}, 6);
}

// The same street with stations tilted up to 5° (no compensator): the 6-DoF estimator's turn.
TEST(HardProjects, BusyTiltedStreetWithCoarseFeatures) {
  const std::vector<Scan> scans = Simulate({6, 1000, 250, 12.0, true, 3, 6, 5.0});
  ExpectAllRegisteredAndNoWrongLink(scans, Register(scans, CoarseScale()));
}

// The tilted street with default options: each scan is levelled by the up its walls and ground
// give (tilts up to 10°), so tilted stations get plan views and the levelled solver too (seeds 5
// and 7: 2 and 2 of 6 scans registered when only tilts below 3° were levelled).
TEST(HardProjects, BusyTiltedStreetIsLevelledByItsWallsAndGround) {
  for (const std::uint64_t seed : {5u, 7u})
    ExpectMostRegisteredAndNoWrongLink({6, 1000, 250, 12.0, true, seed, 6, 5.0}, 5);
}

// Seed 3 of it: two stations' plan-view links all fit to 2 mm, and all carry traffic in each other's
// free space, so each needs a loop, and one such link could not confirm another: 4 of 6 registered.
// Three scans that put a station on one spot confirm it (issue 37): every scan, none wrong.
TEST(HardProjects, BusyTiltedStreetStationsPlacedByThreeAgreeingPlanViewLinks) {
  const std::vector<Scan> scans = Simulate({6, 1000, 250, 12.0, true, 3, 6, 5.0});
  ExpectAllRegisteredAndNoWrongLink(scans, Register(scans, RegisterOptions{}));
}

// Another seed of it, where a station's coarse-scale correspondences (12, weak) fit the street turned
// 180° 25 m away, with a quarter of its points in the other scanner's free space on object-sized
// clusters. Without a loop to confirm it that scan stays unregistered; it is never registered wrong.
TEST(HardProjects, BusyTiltedStreetNeverRegistersAStationTurnedAround) {
  const std::vector<Scan> scans = Simulate({6, 1000, 250, 12.0, true, 7, 6, 5.0});
  const ProjectRegistration r = Register(scans, CoarseScale());
  ASSERT_EQ(r.scans.size(), scans.size());
  const std::vector<ReferenceError> errors = ReferenceErrors(r, scans);
  int registered = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!r.scans[i].registered) {
      EXPECT_FALSE(r.scans[i].reason.empty()) << scans[i].name;
      continue;
    }
    ++registered;
    EXPECT_LE(errors[i].position_m, 0.02) << scans[i].name;
    EXPECT_LE(errors[i].angle_rad * kDeg, 0.1) << scans[i].name;
  }
  EXPECT_GE(registered, 5);
  int turned = 0;  // links a metre or more off: the data holds the wrong pose the test is about
  for (const io::LinkRecord& l : r.links) {
    const PoseError e = *LinkReferenceError(l, scans);
    turned += e.angle_rad * kDeg > 90.0;
    if (l.status == io::LinkStatus::kFailed) continue;
    EXPECT_LE(e.position_m, 0.05) << l.parent << "-" << l.child << " accepted but wrong (" << l.method << ")";
  }
  EXPECT_GE(turned, 1) << "no link turned around: the test would prove nothing";
}

TEST(HardProjects, LowResolutionScans) {
  const std::vector<Scan> scans = Simulate({4, 600, 150, 5.0, true, 5});
  ExpectAllRegisteredAndNoWrongLink(scans, Register(scans, RegisterOptions{}));
}

TEST(HardProjects, ScansWithoutReflectance) {
  const std::vector<Scan> scans = Simulate({4, 1000, 250, 5.0, false, 6});
  ASSERT_FALSE(scans.empty());
  for (std::size_t i = 0; i < scans[0].size(); ++i)
    if (scans[0].valid[i]) ASSERT_EQ(scans[0].reflectance[i], 0.5f);
  const ProjectRegistration r = Register(scans, RegisterOptions{});
  ExpectAllRegisteredAndNoWrongLink(scans, r);
  for (const io::LinkRecord& l : r.links) EXPECT_EQ(l.ransac_inliers, l.geometric_inliers) << "no SIFT without reflectance";
  RegisterOptions sift_only;
  sift_only.features = FeatureSources::kSift;
  EXPECT_LE(CountRegistered(Register(scans, sift_only)), 1);
}

// Exported unorganized (a PLY of x y z intensity in shuffled order, as many programs write TLS
// scans): the reader rebuilds each scan's angular grid, and the project registers as before.
TEST(HardProjects, UnorganizedExports) {
  const std::vector<Scan> organized = Simulate({4, 1000, 250, 5.0, true, 9});
  ASSERT_EQ(organized.size(), 4u);
  test::TempDir dir;
  std::vector<Scan> scans;
  std::mt19937 rng(11);
  for (const Scan& s : organized) {
    std::vector<std::size_t> order;
    for (std::size_t i = 0; i < s.size(); ++i)
      if (s.valid[i]) order.push_back(i);
    std::shuffle(order.begin(), order.end(), rng);
    const std::filesystem::path file = dir / (s.name + ".ply");
    {
      std::ofstream out(file);
      out << "ply\nformat ascii 1.0\nelement vertex " << order.size()
          << "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\nend_header\n";
      out.precision(7);
      for (std::size_t i : order)
        out << s.points[i].x() << ' ' << s.points[i].y() << ' ' << s.points[i].z() << ' ' << s.reflectance[i] << '\n';
    }
    NullProgress progress;
    Expected<std::vector<Scan>> read = io::ReadScanFile(file, progress, CancelToken());
    ASSERT_TRUE(read.ok()) << read.error().ToString();
    ASSERT_EQ(read->size(), 1u);
    Scan scan = std::move(read->front());
    EXPECT_GT(scan.CountValid(), 0.9 * order.size()) << "the rebuilt grid keeps nearly every point";
    scan.name = s.name;
    scan.reference_world_from_scan = s.reference_world_from_scan;
    scans.push_back(std::move(scan));
  }
  ExpectAllRegisteredAndNoWrongLink(scans, Register(scans, RegisterOptions{}));
}

// The plan view's wall map does not depend on the resolution: one station scanned at 1000 x 250
// and at W's 3000 x 750 shows the same walls. Walls were found up a column within a fixed 8 rows —
// 2.9° at 1000 x 250, 0.96° at 3000 x 750 — so at the finer resolution only walls at least 19 m
// away were mapped (6.5 m at the coarser), and stations 25 m apart got wrong plan-view poses.
TEST(HardProjects, PlanViewMapsTheSameWallsAtAnyResolution) {
  std::vector<std::unordered_set<std::int64_t>> occupied;  // 0.5 m cells holding a wall
  for (const auto& [cols, rows] : {std::make_pair(1000, 250), std::make_pair(3000, 750)}) {
    const std::vector<Scan> scans = Simulate({1, cols, rows, 25.0, false, 5});
    ASSERT_EQ(scans.size(), 1u);
    GeometricOptions g;
    g.voxel_m = SuggestVoxel(scans[0]);
    CancelToken cancel;
    Expected<GeometricFeatures> f = DetectGeometricFeatures(scans[0], g, cancel);
    ASSERT_TRUE(f.ok()) << f.error().ToString();
    const PlanView view = MakePlanView(*f, scans[0]);
    ASSERT_TRUE(view.usable);
    std::unordered_set<std::int64_t> cells;
    for (const Eigen::Vector2d& p : view.wall_xy)
      cells.insert(std::int64_t(std::floor(p.x() / 0.5)) * 100000 + std::int64_t(std::floor(p.y() / 0.5)));
    occupied.push_back(std::move(cells));
  }
  int shared = 0;  // the coarser map's wall cells with a wall at the finer resolution there or next to it
  for (std::int64_t c : occupied[0]) {
    bool found = false;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy) found |= occupied[1].count(c + dx * 100000 + dy) > 0;
    shared += found;
  }
  std::printf("wall cells: %zu at 1000 x 250, %zu at 3000 x 750, %d of the first at or next to one of the second\n",
              occupied[0].size(), occupied[1].size(), shared);
  EXPECT_GE(occupied[0].size(), 100u);
  EXPECT_GE(shared, 0.95 * occupied[0].size());
}

// The plan-view search alone (no correspondence): two levelled scans 15 m apart, the best
// hypothesis within the fine step's reach of the truth (0.5 m, 1°).
TEST(HardProjects, PlanViewFindsTheHeadingAndTranslation) {
  const std::vector<Scan> scans = Simulate({2, 1000, 250, 15.0, false, 7});
  ASSERT_EQ(scans.size(), 2u);
  GeometricOptions g;
  g.voxel_m = SuggestVoxel(scans[0]);
  CancelToken cancel;
  std::vector<PlanView> views;
  std::vector<Eigen::Isometry3d> level;
  for (const Scan& s : scans) {
    Expected<GeometricFeatures> f = DetectGeometricFeatures(s, g, cancel);
    ASSERT_TRUE(f.ok()) << f.error().ToString();
    EXPECT_TRUE(f->levelled) << s.name << " tilt " << f->tilt_rad * kDeg << "°";
    views.push_back(MakePlanView(*f, s));
    level.push_back(f->Levelling());
  }
  const std::vector<PlanHypothesis> h = PlanHypotheses(views[0], views[1]);
  ASSERT_FALSE(h.empty());
  const Eigen::Isometry3d truth = scans[0].reference_world_from_scan->inverse() * *scans[1].reference_world_from_scan;
  const PoseError e = ComparePoses(level[0].inverse() * h[0].parent_from_child * level[1], truth);
  EXPECT_LE(e.position_m, 0.5);
  EXPECT_LE(e.angle_rad * kDeg, 1.0);
  // Swapping the scans gives the inverse.
  const std::vector<PlanHypothesis> back = PlanHypotheses(views[1], views[0]);
  ASSERT_FALSE(back.empty());
  const PoseError eb = ComparePoses(level[1].inverse() * back[0].parent_from_child * level[0], truth.inverse());
  EXPECT_LE(eb.position_m, 0.5);
}

}  // namespace
}  // namespace scanreg::pipeline
