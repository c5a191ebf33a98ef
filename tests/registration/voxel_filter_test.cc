#include "core/registration/voxel_filter.h"

#include <gtest/gtest.h>

#include <limits>

namespace scanreg {
namespace {

TEST(VoxelFilter, KeepsOneCentroidPerVoxel) {
  const std::vector<Eigen::Vector3d> pts = {
      {0.01, 0.01, 0.01}, {0.09, 0.05, 0.03},  // voxel (0,0,0)
      {0.15, 0.0, 0.0},                        // voxel (1,0,0)
      {-0.05, 0.0, 0.0}, {-0.01, 0.02, 0.0},   // voxel (-1,0,0)
      {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}};
  const auto out = VoxelDownsample(pts, 0.1);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_NEAR((out[0] - Eigen::Vector3d(0.05, 0.03, 0.02)).norm(), 0.0, 1e-12);  // first-hit order
  EXPECT_NEAR((out[1] - pts[2]).norm(), 0.0, 1e-12);
  EXPECT_NEAR((out[2] - Eigen::Vector3d(-0.03, 0.01, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_EQ(VoxelDownsample(pts, 0.0).size(), 5u);  // no downsampling, NaN dropped
}

TEST(VoxelFilter, DenseGridReducesToVoxelCount) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 100; ++i)
    for (int j = 0; j < 100; ++j) pts.emplace_back(0.01 * i + 0.005, 0.01 * j + 0.005, 2.0);  // 1 x 1 m plane
  EXPECT_EQ(VoxelDownsample(pts, 0.1).size(), 100u);
}

}  // namespace
}  // namespace scanreg
