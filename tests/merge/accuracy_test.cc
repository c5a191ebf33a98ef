// Issue 35: the default merge is closer to the truth than the points it merges, invents no surface,
// and beats TSDF — measured against the noise-free scene of a simulated street (the same stations
// with every noise source off), as `scanreg-bench --section merge` measures the larger projects.
#include <gtest/gtest.h>

#include <cstdio>

#include "core/merge/merge.h"
#include "core/pipeline/merge_scans.h"
#include "core/simulate/project_sim.h"
#include "tests/merge/truth_surface.h"

namespace scanreg::merge {
namespace {

TEST(MergeAccuracy, TheConsensusIsCloserToTheTruthThanItsInputPointsAndTsdf) {
  SimulatedProjectOptions po;
  po.stations = 2;
  po.scanner.cols = 750;
  po.scanner.rows = 188;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(po, progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  SimulatedProjectOptions noise_free = po;
  noise_free.scanner.range_noise_m = noise_free.scanner.range_noise_per_m = noise_free.scanner.angle_noise_deg = 0.0;
  Expected<std::vector<Scan>> truth_scans = SimulateProject(noise_free, progress, cancel);
  ASSERT_TRUE(truth_scans.ok()) << truth_scans.error().ToString();
  constexpr double kRange = 25.0, kVoxel = 0.08;  // 750 x 188 cells are ~8 cm apart at 10 m
  const test::TruthSurface truth(*truth_scans, kRange);
  std::vector<Eigen::Vector3d> input;
  for (Scan& s : *scans) {
    s.world_from_scan = *s.reference_world_from_scan;
    for (std::size_t k = 0; k < s.size(); k += 3)
      if (s.valid[k] && s.points[k].norm() <= kRange) input.push_back(s.world_from_scan * s.points[k].cast<double>());
  }
  const test::Accuracy of_input = test::Measure(truth, input);
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
    of[m] = test::Measure(truth, vertices);
    holes[m] = truth.Holes(vertices, kVoxel);
    std::printf("%s: RMS %.2f mm to the noise-free scene (input points %.2f mm), %.2f %% spurious, %.1f %% holes\n",
                MergeMethodName(methods[m]), 1e3 * of[m].rms_m, 1e3 * of_input.rms_m, 100 * of[m].spurious,
                100 * holes[m]);
  }
  EXPECT_LE(of[0].rms_m, 0.8 * of_input.rms_m);
  EXPECT_LE(of[0].rms_m, of[1].rms_m);
  EXPECT_LE(of[0].spurious, 0.005);
  EXPECT_LE(holes[0], holes[1]);
}

}  // namespace
}  // namespace scanreg::merge
