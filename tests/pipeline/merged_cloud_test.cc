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
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

TEST(MergedCloud, RegistersWithTripodStationsOnEvidenceItHas) {
  SimulatedProjectOptions o;
  o.stations = 6;
  o.spacing_m = 8;
  o.scanner.cols = 1000;
  o.scanner.rows = 250;
  o.seed = o.scanner.seed = o.scene.seed = 21;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> sim = SimulateProject(o, progress, cancel);
  ASSERT_TRUE(sim.ok()) << sim.error().ToString();
  // Stations 1, 3, 5 stay tripod scans; 0, 2, 4 are merged into one cloud at their true poses.
  std::vector<Scan> scans;
  std::vector<Eigen::Vector3f> merged;
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
      reflectance.push_back(s.reflectance[k]);
    }
  }
  std::vector<std::size_t> order(merged.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::shuffle(order.begin(), order.end(), std::mt19937(5));
  std::vector<Eigen::Vector3f> shuffled;
  std::vector<float> shuffled_reflectance;
  for (std::size_t k : order) shuffled.push_back(merged[k]), shuffled_reflectance.push_back(reflectance[k]);
  Expected<Scan> cloud = io::OrganizeCloudByDensity(shuffled, shuffled_reflectance, "merged", "merged.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.error().ToString();
  EXPECT_EQ(cloud->CountPoints(), merged.size());
  EXPECT_FALSE(cloud->single_viewpoint);
  cloud->reference_world_from_scan = Eigen::Isometry3d::Identity();
  scans.push_back(std::move(*cloud));

  Expected<ProjectRegistration> r = RegisterScans(scans, {}, RegisterOptions(), progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const int n = static_cast<int>(scans.size());
  const int root = r->root;
  ASSERT_GE(root, 0);
  for (int i = 0; i < n; ++i) {
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

}  // namespace
}  // namespace scanreg::pipeline
