// Issue 34: a cloud merged from several stations (another program's registered export: world
// coordinates, the points shuffled) is a first-class scan. It is imported with every point, and
// registered with tripod stations of the same street, and no link of it is judged on free space
// "seen" from its origin, a viewpoint it does not have.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/organize_default.h"
#include "core/pipeline/moving_points.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/scale_defaults.h"
#include "core/registration/ray_free_space.h"
#include "core/registration/visibility.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// Six stations of a street 8 m apart: 1, 3, 5 stay tripod scans; 0, 2, 4 are merged into one cloud
// at their true poses (world coordinates, the points shuffled), with each point's station as its
// sensor position when `with_sensor`; `movers` vehicles and as many pedestrians placed anew in every scan.
std::vector<Scan> TripodsAndMergedCloud(bool with_sensor, int movers = 0) {
  SimulatedProjectOptions o;
  o.traffic.vehicles = o.traffic.pedestrians = movers;
  o.stations = 6;
  o.spacing_m = 8;
  o.scanner.cols = 1000;
  o.scanner.rows = 250;
  o.seed = o.scanner.seed = o.scene.seed = 21;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> sim = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(sim.ok()) << sim.error().ToString();
  if (!sim.ok()) return {};
  std::vector<Scan> scans;
  std::vector<Eigen::Vector3f> merged, origin;
  std::vector<float> reflectance;
  for (std::size_t i = 0; i < sim->size(); ++i) {
    const Scan& s = (*sim)[i];
    if (i % 2 == 1) {
      scans.push_back(s);
      continue;
    }
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (!s.valid[k]) continue;
      merged.push_back((*s.reference_world_from_scan * s.points[k].cast<double>()).cast<float>());
      origin.push_back(s.reference_world_from_scan->translation().cast<float>());
      reflectance.push_back(s.reflectance[k]);
    }
  }
  std::vector<std::size_t> order(merged.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  std::vector<Eigen::Vector3f> shuffled, shuffled_origin;
  std::vector<float> shuffled_reflectance;
  for (std::size_t k : order) {
    shuffled.push_back(merged[k]);
    shuffled_origin.push_back(origin[k]);
    shuffled_reflectance.push_back(reflectance[k]);
  }
  Expected<Scan> cloud = io::OrganizeCloudByDensity(shuffled, shuffled_reflectance, "merged", "merged.ply", {}, {},
                                                    with_sensor ? shuffled_origin : std::vector<Eigen::Vector3f>());
  EXPECT_TRUE(cloud.ok()) << cloud.error().ToString();
  if (!cloud.ok()) return {};
  EXPECT_EQ(cloud->CountPoints(), merged.size());
  EXPECT_FALSE(cloud->single_viewpoint);
  EXPECT_EQ(cloud->HasSensor(), with_sensor);
  cloud->reference_world_from_scan = Eigen::Isometry3d::Identity();
  scans.push_back(std::move(*cloud));
  return scans;
}

// Registers the scans with default options; every scan registered within 2 cm / 0.1° of the truth.
void ExpectEveryScanAtTheTruth(const std::vector<Scan>& scans, ProjectRegistration* out) {
  NullProgress progress;
  CancelToken cancel;
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, RegisterOptions(), progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const int root = r->root;
  ASSERT_GE(root, 0);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    SCOPED_TRACE(scans[i].name);
    EXPECT_TRUE(r->scans[i].registered) << r->scans[i].reason;
    if (!r->scans[i].registered) continue;
    const PoseError e =
        ComparePoses(r->scans[root].world_from_scan.inverse() * r->scans[i].world_from_scan,
                     scans[root].reference_world_from_scan->inverse() * *scans[i].reference_world_from_scan);
    std::printf("%s: %.1f mm %.3f deg from the truth\n", scans[i].name.c_str(), 1e3 * e.position_m, e.angle_rad * kDeg);
    EXPECT_LT(e.position_m, 0.02);
    EXPECT_LT(e.angle_rad * kDeg, 0.1);
  }
  *out = std::move(*r);
}

TEST(MergedCloud, RegistersWithTripodStationsOnEvidenceItHas) {
  const std::vector<Scan> scans = TripodsAndMergedCloud(false);
  ASSERT_EQ(scans.size(), 4u);
  ProjectRegistration registration;
  ExpectEveryScanAtTheTruth(scans, &registration);
  const ProjectRegistration* r = &registration;
  // The cloud's links are judged on overlap, residual, agreement and the tripod scanners' free
  // space, never on free space seen from the cloud's origin.
  int links_of_cloud = 0;
  for (const io::LinkRecord& l : r->links) {
    if (l.parent != "merged" && l.child != "merged") continue;
    ++links_of_cloud;
    std::printf("%s -> %s: %s %s\n", l.child.c_str(), l.parent.c_str(), io::LinkStatusName(l.status), l.reason.c_str());
    EXPECT_EQ(l.reason.find("free space"), std::string::npos) << l.reason;
  }
  EXPECT_GE(links_of_cloud, 1);
}

// With each point's sensor position, the cloud sees free space along its rays (issue 34): at the
// true pose a tripod station's samples lie on the cloud's surfaces, at a pose 3 m along the street
// or turned round they lie where its sensors saw through; without sensor positions nothing is
// tested from the cloud.
TEST(MergedCloud, SeesFreeSpaceAlongItsRaysWhereTheFileGivesThem) {
  const std::vector<Scan> with = TripodsAndMergedCloud(true);
  const std::vector<Scan> without = TripodsAndMergedCloud(false);
  ASSERT_EQ(with.size(), 4u);
  ASSERT_EQ(without.size(), 4u);
  const Scan& cloud = with[3];
  EXPECT_FALSE(HasViewpoint(cloud));
  FreeSpaceOptions options;  // 0.2 m margin: cubes of 0.1 m
  const RayFreeSpace rays(cloud, 0.5 * options.margin_m);
  ASSERT_TRUE(rays.known());
  EXPECT_GT(rays.rays(), 10000);
  for (int t = 0; t < 3; ++t) {
    const Scan& tripod = with[t];
    SCOPED_TRACE(tripod.name);
    const Eigen::Isometry3d truth = *tripod.reference_world_from_scan;  // the cloud's frame is the world
    const FreeSpaceResult right = FreeSpaceViolations(cloud, tripod, truth, options, &rays);
    const Eigen::Isometry3d along = Eigen::Translation3d(3.0, 0.0, 0.0) * truth;
    const Eigen::Isometry3d turned = truth * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ());
    const FreeSpaceResult shifted = FreeSpaceViolations(cloud, tripod, along, options, &rays);
    const FreeSpaceResult round = FreeSpaceViolations(cloud, tripod, turned, options, &rays);
    std::printf("%s: tested %d; in free space (static) %.2f (%.2f) %% at the truth, %.2f (%.2f) %% 3 m along, "
                "%.2f (%.2f) %% turned round\n",
                tripod.name.c_str(), right.tested, 100 * right.fraction(), 100 * right.static_fraction(),
                100 * shifted.fraction(), 100 * shifted.static_fraction(), 100 * round.fraction(),
                100 * round.static_fraction());
    EXPECT_GT(right.tested, 5000);
    EXPECT_LT(right.fraction(), 0.01);
    // Along a street of façades only the objects conflict (as a tripod's range image sees it:
    // 5-10 % in free space, 0-1.5 % of it static); turned round, the façades do.
    EXPECT_GT(shifted.fraction(), 0.03);
    EXPECT_GT(round.static_fraction(), 0.05);
    EXPECT_EQ(FreeSpaceViolations(without[3], tripod, truth, options, nullptr).tested, 0);
    // The tripod's own range image judges the cloud's samples as before.
    EXPECT_GT(FreeSpaceViolations(tripod, cloud, truth.inverse(), options).tested, 0);
  }
  // The registration's evidence uses the rays: a pair's test counts the tripod's samples the cloud's
  // rays see, on top of the cloud's samples the tripod sees.
  Expected<RegisterOptions> resolved = ResolveLengths(RegisterOptions(), {&with[0], &with[1], &with[2], &cloud});
  ASSERT_TRUE(resolved.ok()) << resolved.error().ToString();
  const RegisterOptions& register_options = *resolved;
  PreparedScan cloud_with, cloud_without, tripod;
  PrepareScan(cloud, register_options, &cloud_with);
  PrepareScan(without[3], register_options, &cloud_without);
  PrepareScan(with[0], register_options, &tripod);
  ASSERT_NE(cloud_with.rays, nullptr);
  EXPECT_EQ(cloud_without.rays, nullptr);
  EXPECT_EQ(tripod.rays, nullptr);  // a scanner's range image is its viewpoint
  const Eigen::Isometry3d turned =
      *with[0].reference_world_from_scan * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ());
  const double d = register_options.overlap_distance_m;
  const AlignmentEvidence seen = EvaluateAlignment(cloud_with, tripod, turned, d);
  const AlignmentEvidence unseen = EvaluateAlignment(cloud_without, tripod, turned, d);
  EXPECT_GT(seen.tested, unseen.tested);
  EXPECT_GT(seen.conflict, 0.05);
}

// The merge leaves out moving objects: a tripod's points in another scanner's free space. Where
// the cloud gives its sensor positions, its rays find them as a tripod's range image does, and
// mark no more static points on a street without traffic than a range image.
TEST(MergedCloud, ItsRaysFindTheTrafficInTheTripodScans) {
  // Each tripod's points marked by one observer: the cloud (3), or the next tripod (its range image).
  auto marked = [](std::vector<Scan> scans, int observer, std::size_t* points) {
    for (Scan& s : scans) s.world_from_scan = *s.reference_world_from_scan;  // registered at the truth
    std::size_t n = 0;
    *points = 0;
    for (int t = 0; t < 3; ++t) {
      const int o = observer == 3 ? 3 : (t + 1) % 3;
      auto cells = MovingPointCells(merge::ScansInMemory({&scans[t], &scans[o]}),
                                    {scans[t].world_from_scan, scans[o].world_from_scan}, MovingPointOptions(),
                                    CancelToken());
      EXPECT_TRUE(cells.ok()) << cells.error().ToString();
      if (!cells.ok()) return n;
      n += (*cells)[0].size();
      *points += scans[t].CountValid();
    }
    return n;
  };
  std::size_t points = 0;
  const std::vector<Scan> busy = TripodsAndMergedCloud(true, 6), quiet = TripodsAndMergedCloud(true, 0);
  const std::size_t busy_rays = marked(busy, 3, &points), quiet_rays = marked(quiet, 3, &points);
  const std::size_t busy_grid = marked(busy, 0, &points), quiet_grid = marked(quiet, 0, &points);
  const std::size_t busy_none = marked(TripodsAndMergedCloud(false, 6), 3, &points);
  std::printf("tripod points marked as moving (of %zu): by the cloud's rays %zu busy, %zu quiet; by the next tripod's "
              "range image %zu busy, %zu quiet; by the cloud without sensor positions %zu\n",
              points, busy_rays, quiet_rays, busy_grid, quiet_grid, busy_none);
  EXPECT_EQ(busy_none, 0u);
  // A range image marks some static points too (grazing surfaces, mixed pixels): the rays no more
  // than it, and the traffic above that as a range image finds it.
  EXPECT_LT(double(quiet_rays), 1.5 * double(quiet_grid));
  EXPECT_GT(busy_rays, 2 * quiet_rays);
  EXPECT_GT(double(busy_rays) - double(quiet_rays), 0.5 * (double(busy_grid) - double(quiet_grid)));
}

// Registered with its sensor positions, the cloud lands as without them: every scan within
// 2 cm / 0.1° of the truth.
TEST(MergedCloud, WithSensorPositionsRegistersWithTripodStations) {
  const std::vector<Scan> scans = TripodsAndMergedCloud(true);
  ASSERT_EQ(scans.size(), 4u);
  ProjectRegistration registration;
  ExpectEveryScanAtTheTruth(scans, &registration);
  const ProjectRegistration* r = &registration;
  for (const io::LinkRecord& l : r->links)
    if (l.parent == "merged" || l.child == "merged")
      std::printf("%s -> %s: %s, conflict %.2f %%, %s\n", l.child.c_str(), l.parent.c_str(),
                  io::LinkStatusName(l.status), 100 * l.conflict, l.reason.c_str());
}

}  // namespace
}  // namespace scanreg::pipeline
