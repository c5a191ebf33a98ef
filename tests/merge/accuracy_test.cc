// Issue 35: the default merge is closer to the truth than the points it merges, invents no surface,
// and beats TSDF — measured against the noise-free scene of a simulated street (the same stations
// with every noise source off), as `scanreg-bench --section merge` measures the larger projects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>

#include "core/merge/merge.h"
#include "core/merge/vertex_info.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/project_scans.h"
#include "core/simulate/project_sim.h"
#include "tests/merge/truth_surface.h"
#include "tests/support/test_paths.h"

namespace scanreg::merge {
namespace {

constexpr double kRange = 25.0, kVoxel = 0.08;  // 750 x 188 cells are ~8 cm apart at 10 m

// Two street stations 750 x 188 at their true poses, and the truth: the same stations without noise.
class MergeAccuracy : public ::testing::Test {
 protected:
  void SetUp() override {
    po.stations = 2;
    po.scanner.cols = 750;
    po.scanner.rows = 188;
    Expected<std::vector<Scan>> simulated = SimulateProject(po, progress, cancel);
    ASSERT_TRUE(simulated.ok()) << simulated.error().ToString();
    SimulatedProjectOptions noise_free = po;
    noise_free.scanner.range_noise_m = noise_free.scanner.range_noise_per_m = noise_free.scanner.angle_noise_deg = 0.0;
    Expected<std::vector<Scan>> truth_scans = SimulateProject(noise_free, progress, cancel);
    ASSERT_TRUE(truth_scans.ok()) << truth_scans.error().ToString();
    stations = std::move(*simulated);
    for (Scan& s : stations) s.world_from_scan = *s.reference_world_from_scan;
    truth = std::make_unique<test::TruthSurface>(*truth_scans, kRange);
  }
  SimulatedProjectOptions po;
  std::vector<Scan> stations;
  std::unique_ptr<test::TruthSurface> truth;
  NullProgress progress;
  CancelToken cancel;
};

TEST_F(MergeAccuracy, TheConsensusIsCloserToTheTruthThanItsInputPointsAndTsdf) {
  const std::vector<Scan>* scans = &stations;
  std::vector<Eigen::Vector3d> input;
  for (const Scan& s : *scans) {
    for (std::size_t k = 0; k < s.size(); k += 3)
      if (s.valid[k] && s.points[k].norm() <= kRange) input.push_back(s.world_from_scan * s.points[k].cast<double>());
  }
  const test::Accuracy of_input = test::Measure(*truth, input);
  MergeOptions defaults;
  ASSERT_EQ(defaults.method, MergeMethod::kConsensus);
  test::Accuracy of[2];
  double holes[2];
  const MergeMethod methods[2] = {MergeMethod::kConsensus, MergeMethod::kTsdf};
  for (int m = 0; m < 2; ++m) {
    MergeOptions o;
    o.voxel_m = kVoxel;
    o.sigma_m = po.scanner.range_noise_m;
    o.max_range_m = kRange;
    o.method = methods[m];
    Expected<MergeResult> r = pipeline::MergeScans(*scans, {}, o, progress, cancel);  // as the CLI merges
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    std::vector<Eigen::Vector3d> vertices;
    for (const Eigen::Vector3f& v : r->mesh.vertices) vertices.push_back(r->mesh.origin + v.cast<double>());
    ASSERT_GT(vertices.size(), 10000u);
    of[m] = test::Measure(*truth, vertices);
    holes[m] = truth->Holes(vertices, kVoxel);
    std::printf("%s: RMS %.2f mm to the noise-free scene (input points %.2f mm), %.2f %% spurious, %.1f %% holes\n",
                MergeMethodName(methods[m]), 1e3 * of[m].rms_m, 1e3 * of_input.rms_m, 100 * of[m].spurious,
                100 * holes[m]);
  }
  EXPECT_LE(of[0].rms_m, 0.8 * of_input.rms_m);
  EXPECT_LE(of[0].rms_m, of[1].rms_m);
  EXPECT_LE(of[0].spurious, 0.005);
  EXPECT_LE(holes[0], holes[1]);
}

// Issue 34, item 2: a cloud merged from two stations by another program (one PLY in world
// coordinates, shuffled: no viewpoint, most of one station's points off the grid organize builds)
// merges about as well as the two stations it came from: every point joins the surface as a disc on
// the plane of its neighbours, no farther from the truth than its points (consensus; TSDF, which has
// no line of sight to project along, takes the same consensus), nothing invented, about as few holes
// — by every method within 1.5 x the stations' own merge; in one piece or tile by tile alike.
TEST_F(MergeAccuracy, ACloudSeenFromSeveralPlacesMergesAsWellAsTheStationsItCameFrom) {
  const std::vector<Scan>* scans = &stations;
  std::vector<Eigen::Vector3d> cloud;  // what the other program exported: every point within kRange
  for (const Scan& s : *scans) {
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k] && s.points[k].norm() <= kRange) cloud.push_back(s.world_from_scan * s.points[k].cast<double>());
  }
  std::shuffle(cloud.begin(), cloud.end(), std::mt19937(5));
  test::TempDir dir;
  {
    std::FILE* f = std::fopen((dir / "merged.ply").c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty double x\nproperty double y\n"
                 "property double z\nend_header\n", cloud.size());
    for (const Eigen::Vector3d& p : cloud) std::fprintf(f, "%.5f %.5f %.5f\n", p.x(), p.y(), p.z());
    std::fclose(f);
  }
  pipeline::CreateProjectOptions create;
  create.scan_files = {dir / "merged.ply"};
  auto created = pipeline::CreateProject(dir / "p.scanreg.json", create, progress, cancel);
  ASSERT_TRUE(created.ok()) << created.error().ToString();
  auto imported = pipeline::LoadProjectScans(created->project, progress, cancel);
  ASSERT_TRUE(imported.ok()) << imported.error().ToString();
  ASSERT_EQ(imported->size(), 1u);
  ASSERT_FALSE(imported->front().single_viewpoint);
  ASSERT_GT(imported->front().list_points.size(), cloud.size() / 5);  // much of it off the grid

  test::Accuracy of_input = test::Measure(*truth, cloud);
  for (MergeMethod method : {MergeMethod::kConsensus, MergeMethod::kTsdf, MergeMethod::kMaximumLikelihood}) {
    SCOPED_TRACE(MergeMethodName(method));
    MergeOptions o;
    o.voxel_m = kVoxel;
    o.sigma_m = po.scanner.range_noise_m;
    o.max_range_m = kRange;
    o.method = method;
    test::Accuracy of[2];
    double holes[2];
    for (int k = 0; k < 2; ++k) {
      Expected<MergeResult> r = pipeline::MergeScans(k == 0 ? *scans : *imported, {}, o, progress, cancel);
      ASSERT_TRUE(r.ok()) << r.error().ToString();
      std::vector<Eigen::Vector3d> vertices;
      for (const Eigen::Vector3f& v : r->mesh.vertices) vertices.push_back(r->mesh.origin + v.cast<double>());
      ASSERT_GT(vertices.size(), 10000u);
      of[k] = test::Measure(*truth, vertices);
      holes[k] = truth->Holes(vertices, kVoxel);
      std::printf("%s, %s: RMS %.2f mm to the noise-free scene (its points %.2f mm), %.2f %% spurious, %.1f %% holes\n",
                  MergeMethodName(method), k == 0 ? "the two stations" : "their merged cloud", 1e3 * of[k].rms_m,
                  1e3 * of_input.rms_m, 100 * of[k].spurious, 100 * holes[k]);
    }
    EXPECT_LE(of[1].rms_m, 1.5 * of[0].rms_m);
    EXPECT_LE(holes[1], holes[0] + 0.05);
    if (method == MergeMethod::kMaximumLikelihood) {  // S's merge: not the default (issue 35), as its stations
      EXPECT_LE(of[1].spurious, 3 * of[0].spurious + 0.005);
      continue;
    }
    EXPECT_LE(of[1].rms_m, of_input.rms_m);
    EXPECT_LE(of[1].spurious, 0.005);
  }
  // Tile by tile (5 m tiles: each tile's discs from the points within its margin) as in one piece.
  MergeOptions o;
  o.voxel_m = kVoxel;
  o.sigma_m = po.scanner.range_noise_m;
  o.tile_blocks = 4;
  Expected<MergeResult> tiled = pipeline::MergeScans(*imported, {}, o, progress, cancel);
  ASSERT_TRUE(tiled.ok()) << tiled.error().ToString();
  std::vector<Eigen::Vector3d> vertices;
  for (const Eigen::Vector3f& v : tiled->mesh.vertices) vertices.push_back(tiled->mesh.origin + v.cast<double>());
  const test::Accuracy of_tiled = test::Measure(*truth, vertices);
  const double tiled_holes = truth->Holes(vertices, kVoxel);
  std::printf("consensus in 5 m tiles, their merged cloud: RMS %.2f mm, %.2f %% spurious, %.1f %% holes\n",
              1e3 * of_tiled.rms_m, 100 * of_tiled.spurious, 100 * tiled_holes);
  EXPECT_LE(of_tiled.rms_m, of_input.rms_m);
  EXPECT_LE(of_tiled.spurious, 0.005);
  EXPECT_LE(tiled_holes, 0.3);
}

// Issue 35, item 1: a hole stays a hole unless the user asks for it filled, and then every vertex
// of the filled surface is marked. At 4 cm the street's far samples (8 cm apart at 10 m) leave the
// consensus holes; filled, fewer — and each vertex farther than 1.5 voxels from every input point
// (found here by PCL's k-d tree over every point merged, not by the merge's own search) says so.
TEST_F(MergeAccuracy, FilledHolesAreMarkedAndTheMeasuredSurfaceStaysCloserThanItsPoints) {
  constexpr double kFine = 0.04;
  pcl::PointCloud<pcl::PointXYZ>::Ptr input(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Scan& s : stations) {
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (!s.valid[k] || s.points[k].norm() > kRange) continue;
      const Eigen::Vector3d p = s.world_from_scan * s.points[k].cast<double>();
      input->push_back(pcl::PointXYZ(float(p.x()), float(p.y()), float(p.z())));
    }
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(input);
  std::vector<Eigen::Vector3d> every_third;
  for (std::size_t k = 0; k < input->size(); k += 3) every_third.push_back((*input)[k].getVector3fMap().cast<double>());
  const test::Accuracy of_input = test::Measure(*truth, every_third);
  test::Accuracy measured[2];
  double holes[2];
  std::size_t interpolated[2];
  std::vector<Eigen::Vector3d> unmarked[2];  // the measured surface's vertices, without and with the fill
  for (int fill = 0; fill < 2; ++fill) {
    MergeOptions o;
    o.voxel_m = kFine;
    o.sigma_m = po.scanner.range_noise_m;
    o.max_range_m = kRange;
    o.fill_holes = fill == 1;
    Expected<MergeResult> r = pipeline::MergeScans(stations, {}, o, progress, cancel);
    ASSERT_TRUE(r.ok()) << r.error().ToString();
    ASSERT_EQ(r->mesh.info.size(), r->mesh.vertices.size());
    std::vector<Eigen::Vector3d> all, kept, marked_v;  // every vertex; within FilledGap of a point; the others
    std::size_t far_unmarked = 0, marked = 0, marked_near = 0;
    std::vector<int> index(1);
    std::vector<float> d2(1);
    for (std::size_t i = 0; i < r->mesh.vertices.size(); ++i) {
      const Eigen::Vector3d v = r->mesh.origin + r->mesh.vertices[i].cast<double>();
      all.push_back(v);
      const bool is_marked = r->mesh.info[i].gap_m > FilledGap(kFine);
      ASSERT_EQ(tree.nearestKSearch(pcl::PointXYZ(float(v.x()), float(v.y()), float(v.z())), 1, index, d2), 1);
      const double gap = std::sqrt(d2[0]);
      far_unmarked += gap > FilledGap(kFine) + 1e-4 && !is_marked;
      marked += is_marked;
      marked_near += is_marked && gap < 0.5 * kFine;
      (is_marked ? marked_v : kept).push_back(v);
    }
    interpolated[fill] = r->interpolated_vertices;
    EXPECT_EQ(r->interpolated_vertices, marked);
    EXPECT_EQ(far_unmarked, 0u) << "vertices farther than 1.5 voxels from every input point left unmarked";
    if (fill == 0) {  // marked by their distance alone: never beside a measurement
      EXPECT_LE(marked_near, marked / 20 + 5) << "vertices marked though an input point lies within half a voxel";
    }
    unmarked[fill] = kept;
    measured[fill] = test::Measure(*truth, kept);
    const test::Accuracy of_marked = test::Measure(*truth, marked_v);
    holes[fill] = truth->Holes(all, kFine);
    std::printf("consensus at 4 cm, holes %s: %zu vertices, %zu (%.1f %%) marked interpolated (RMS %.2f mm, %.2f %% "
                "spurious); the others RMS %.2f mm, %.2f %% spurious (input points %.2f mm); %.1f %% holes\n",
                fill ? "filled" : "kept", all.size(), marked, 100.0 * marked / all.size(), 1e3 * of_marked.rms_m,
                100 * of_marked.spurious, 1e3 * measured[fill].rms_m, 100 * measured[fill].spurious,
                1e3 * of_input.rms_m, 100 * holes[fill]);
  }
  EXPECT_LT(holes[1], 0.5 * holes[0]);
  EXPECT_GT(interpolated[1], interpolated[0]);
  // The measured surface stays closer to the truth than the points it came from, with the fill too:
  // a vertex that only a filled value made (every cube around its edge has a filled corner) is marked,
  // and every measured vertex of the merge without the fill is there, unmarked, with the fill.
  EXPECT_LE(measured[0].rms_m, 0.8 * of_input.rms_m);
  EXPECT_LE(measured[1].rms_m, 0.8 * of_input.rms_m);
  // What stays unmarked with the fill is the measured surface plus the small measured pieces the fill
  // joins to it (removed as small pieces without it): measured 5.31 -> 6.37 mm. When a vertex was
  // marked by its distance to the points alone, the vertices of cubes with a filled corner beside
  // the measurements counted as measured: 5.31 -> 9.14 mm.
  EXPECT_LE(measured[1].rms_m, 1.25 * measured[0].rms_m);
  EXPECT_LE(measured[1].spurious, 0.005);
  pcl::PointCloud<pcl::PointXYZ>::Ptr with_fill(new pcl::PointCloud<pcl::PointXYZ>);
  for (const Eigen::Vector3d& v : unmarked[1]) with_fill->push_back(pcl::PointXYZ(float(v.x()), float(v.y()), float(v.z())));
  pcl::KdTreeFLANN<pcl::PointXYZ> filled_tree;
  filled_tree.setInputCloud(with_fill);
  std::size_t lost = 0;
  std::vector<int> index(1);
  std::vector<float> d2(1);
  for (const Eigen::Vector3d& v : unmarked[0]) {
    lost += filled_tree.nearestKSearch(pcl::PointXYZ(float(v.x()), float(v.y()), float(v.z())), 1, index, d2) != 1 ||
            d2[0] > 1e-8f;
  }
  std::printf("measured vertices without the fill that the fill marked or moved: %zu of %zu\n", lost, unmarked[0].size());
  EXPECT_LE(lost, unmarked[0].size() / 1000);
}

}  // namespace
}  // namespace scanreg::merge
