// The merge's estimate (issue 16 item 2): the blocks it counts are the blocks the merge allocates,
// an extrapolated count errs on the large side, and a merge beyond the memory budget is refused
// before it starts, with a voxel that does fit.
#include "core/merge/merge_estimate.h"

#include <gtest/gtest.h>

#include "core/pipeline/merge_scans.h"
#include "tests/merge/merge_test_util.h"

namespace scanreg::merge {
namespace {

std::vector<Scan> SphereViews() {
  std::vector<Scan> scans;
  const Eigen::Vector3d c(3.0, -2.0, 1.0);
  int i = 0;
  for (const Eigen::Vector3d& eye : test::AllAroundEyes(c, 3.0)) {
    scans.push_back(test::MakeWindowScan(test::SphereCaster(c, 0.6), eye, c, 120, 120, 0.25, 0.003, 11 + i,
                                         "v" + std::to_string(i)));
    ++i;
  }
  return scans;
}

std::vector<const Scan*> Pointers(const std::vector<Scan>& scans) {
  std::vector<const Scan*> out;
  for (const Scan& s : scans) out.push_back(&s);
  return out;
}

TEST(MergeEstimate, CountsTheBlocksTheMergeAllocates) {
  const std::vector<Scan> scans = SphereViews();
  for (double voxel : {0.01, 0.03}) {
    MergeOptions options;
    options.voxel_m = voxel;
    options.method = MergeMethod::kTsdf;
    NullProgress progress;
    CancelToken cancel;
    Expected<MergeResult> merged = pipeline::MergeScans(scans, {}, options, progress, cancel);
    ASSERT_TRUE(merged.ok()) << merged.error().ToString();
    const MergeEstimate& e = merged->estimate;
    EXPECT_FALSE(e.extrapolated);
    // The estimate counts every valid point (the merge thins dense range images) on a grid of its
    // own origin: the same surface, within a few blocks per cent.
    EXPECT_GT(double(e.blocks), 0.9 * double(merged->blocks)) << "voxel " << voxel;
    EXPECT_LT(double(e.blocks), 1.25 * double(merged->blocks)) << "voxel " << voxel;
    EXPECT_GE(e.bytes, merged->field_bytes) << "voxel " << voxel;
  }
}

// Points merged as discs (a cloud seen from several places, a scan's listed points) cost their
// normals and splats besides the blocks: the same points as one multi-viewpoint cloud are estimated
// to take longer than as range images, on the same blocks, and listed points count like them.
TEST(MergeEstimate, PointsMergedAsDiscsTakeTimeOfTheirOwn) {
  const std::vector<Scan> views = SphereViews();
  MergeOptions options;
  options.voxel_m = 0.02;
  options.method = MergeMethod::kTsdf;
  const MergeEstimate as_images = EstimateMerge(Pointers(views), options);
  std::vector<Scan> clouds = views;
  for (Scan& s : clouds) s.single_viewpoint = false;
  const MergeEstimate as_clouds = EstimateMerge(Pointers(clouds), options);
  EXPECT_EQ(as_clouds.blocks, as_images.blocks);
  EXPECT_GT(as_clouds.seconds, 2.0 * as_images.seconds);
  // The same points listed (no grid cells): the same blocks and the same time as the cloud.
  std::vector<Scan> listed = views;
  for (Scan& s : listed) {
    for (std::size_t i = 0; i < s.size(); ++i) {
      if (!s.valid[i]) continue;
      s.list_points.push_back(s.points[i]);
      s.list_reflectance.push_back(s.reflectance[i]);
      s.valid[i] = 0;
    }
  }
  const MergeEstimate as_lists = EstimateMerge(Pointers(listed), options);
  EXPECT_EQ(as_lists.blocks, as_clouds.blocks);
  EXPECT_NEAR(as_lists.seconds, as_clouds.seconds, 1e-9 + 1e-6 * as_clouds.seconds);
}

TEST(MergeEstimate, AnExtrapolatedCountErrsOnTheLargeSide) {
  const std::vector<Scan> scans = SphereViews();
  MergeOptions options;
  options.voxel_m = 0.004;
  const MergeEstimate counted = EstimateMerge(Pointers(scans), options);
  ASSERT_FALSE(counted.extrapolated);
  const MergeEstimate extrapolated = EstimateMerge(Pointers(scans), options, counted.blocks / 10);
  ASSERT_TRUE(extrapolated.extrapolated);
  EXPECT_GE(double(extrapolated.blocks), 0.9 * double(counted.blocks));
  EXPECT_LT(double(extrapolated.blocks), 2.0 * double(counted.blocks));
}

TEST(MergeEstimate, AMergeBeyondTheBudgetIsRefusedWithAVoxelThatFits) {
  const std::vector<Scan> scans = SphereViews();
  MergeOptions options;
  options.voxel_m = 0.002;
  const MergeEstimate need = EstimateMerge(Pointers(scans), options);
  options.memory_budget_bytes = need.bytes / 4;
  NullProgress progress;
  CancelToken cancel;
  Expected<MergeResult> merged = pipeline::MergeScans(scans, {}, options, progress, cancel);
  ASSERT_FALSE(merged.ok());
  const std::string message = merged.error().ToString();
  EXPECT_NE(message.find("memory budget"), std::string::npos) << message;
  // The voxel it names fits the same budget.
  const std::size_t at = message.find("A voxel of ");
  ASSERT_NE(at, std::string::npos) << message;
  const double fit = std::stod(message.substr(at + 11));
  EXPECT_GT(fit, options.voxel_m);
  options.voxel_m = fit;
  MergeEstimate estimate;
  EXPECT_TRUE(CheckMergeFits(Pointers(scans), options, &estimate).ok()) << estimate.Describe();
  EXPECT_LE(estimate.bytes, options.memory_budget_bytes);
}

// A merge that spills its mesh to disk (the CLI's) needs the mesh's bytes on disk, not in memory:
// the same estimate otherwise, and a budget that refuses the mesh in memory lets it through.
TEST(MergeEstimate, AMeshSpilledToDiskIsCountedOnDisk) {
  const std::vector<Scan> scans = SphereViews();
  MergeOptions options;
  options.voxel_m = 0.004;
  const MergeEstimate held = EstimateMerge(Pointers(scans), options);
  const MergeEstimate spilled = EstimateMerge(Pointers(scans), options, 50'000'000, {}, true);
  EXPECT_EQ(held.disk_bytes, 0u);
  EXPECT_GT(held.bytes - spilled.bytes, held.bytes / 4) << "the mesh is a large share of a merge's memory";
  EXPECT_GT(spilled.disk_bytes, (held.bytes - spilled.bytes) / 4) << "its files: 12 bytes a vertex and a triangle";
  EXPECT_LT(spilled.disk_bytes, held.bytes - spilled.bytes);
  EXPECT_EQ(spilled.blocks, held.blocks);
  EXPECT_NE(spilled.Describe().find("on disk"), std::string::npos) << spilled.Describe();
  options.memory_budget_bytes = (spilled.bytes + held.bytes) / 2;
  MergeEstimate estimate;
  EXPECT_FALSE(CheckMergeFits(Pointers(scans), options, &estimate).ok());
  EXPECT_TRUE(CheckMergeFits(Pointers(scans), options, &estimate, {}, true).ok()) << estimate.Describe();
}

}  // namespace
}  // namespace scanreg::merge
