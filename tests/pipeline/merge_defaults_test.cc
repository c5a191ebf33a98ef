// Merge defaults sized to the project (issue 14, item 8): the voxel follows the data's scale and
// grows until the estimate fits the time asked for.
#include <gtest/gtest.h>

#include "core/pipeline/merge_scans.h"

namespace scanreg::pipeline {
namespace {

// A hemisphere of the given radius seen from its centre: rows x cols returns.
Scan Dome(double radius_m, int rows, int cols) {
  Scan scan("dome", rows, cols);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const double el = 0.5 * M_PI * r / rows, az = 2 * M_PI * c / cols;
      scan.Set(r, c,
               Eigen::Vector3f(radius_m * std::cos(el) * std::cos(az), radius_m * std::cos(el) * std::sin(az),
                               radius_m * std::sin(el)),
               0.5f);
    }
  return scan;
}

TEST(SizedMergeOptions, TheVoxelFollowsTheScaleAndGrowsToFitTheTime) {
  const Scan small = Dome(0.1, 200, 800);   // a 20 cm object
  const Scan large = Dome(50.0, 200, 800);  // a 100 m site
  MergeEstimate e_small, e_large;
  const MergeOptions a = SizedMergeOptions({&small}, MergeOptions(), 600.0, &e_small);
  const MergeOptions b = SizedMergeOptions({&large}, MergeOptions(), 600.0, &e_large);
  EXPECT_LT(a.voxel_m, 0.005) << "a 20 cm object needs millimetre voxels";
  EXPECT_GE(a.voxel_m, 0.001);
  EXPECT_GE(b.voxel_m, 0.02);
  EXPECT_GT(e_small.blocks, 0u);
  EXPECT_LE(e_large.seconds, 600.0);
  // Asked for a merge a hundred times quicker than its estimate, the voxel grows and the estimate drops.
  MergeEstimate quick;
  const MergeOptions c = SizedMergeOptions({&large}, MergeOptions(), e_large.seconds / 100.0, &quick);
  EXPECT_GT(c.voxel_m, b.voxel_m);
  EXPECT_LT(quick.seconds, e_large.seconds);
}

}  // namespace
}  // namespace scanreg::pipeline
