// FPFH at two scales (issue 37, item 2): the fine scale is what it was without the coarse one (the
// levelling and the plan view read only it), the coarse scale's samples are coarser, and matches
// pair samples of the same scale only.
#include <gtest/gtest.h>

#include <cmath>

#include "core/registration/geometric_features.h"
#include "tests/registration/synthetic_room.h"

namespace scanreg {
namespace {

GeometricFeatures Detect(const Scan& scan, double coarse_scale) {
  GeometricOptions o;
  o.voxel_m = 0.15;
  o.coarse_scale = coarse_scale;
  CancelToken cancel;
  Expected<GeometricFeatures> f = DetectGeometricFeatures(scan, o, cancel);
  EXPECT_TRUE(f.ok()) << f.error().ToString();
  return f.ok() ? *f : GeometricFeatures{};
}

TEST(GeometricFeatures, TheCoarseScaleAddsCoarserSamplesAndLeavesTheFineScaleAsItWas) {
  const Scan scan = testing::CastRoomScan(testing::RoomStation(-2.0, 1.0, 20.0), 200, 800, testing::DefaultRoom(),
                                          testing::DefaultBlocks(), 0.002);
  const GeometricFeatures one = Detect(scan, 0.0);
  const GeometricFeatures two = Detect(scan, 3.0);
  ASSERT_EQ(one.scales.size(), 1u);
  ASSERT_EQ(two.scales.size(), 2u);
  EXPECT_DOUBLE_EQ(two.scales[1].voxel_m, 0.45);
  ASSERT_GT(one.FinestEnd(), 100);
  ASSERT_EQ(two.FinestEnd(), one.FinestEnd());
  for (int i = 0; i < one.FinestEnd(); ++i) ASSERT_EQ(two.points[i], one.points[i]) << i;
  EXPECT_EQ(two.levelled, one.levelled);
  EXPECT_EQ(two.up, one.up);
  // The coarse samples are fewer (a third of the voxel: about a ninth on surfaces) and spaced wider.
  const int coarse = two.scales[1].end - two.scales[1].begin;
  EXPECT_GT(coarse, 20);
  EXPECT_LT(coarse, one.FinestEnd() / 4);
  EXPECT_EQ(two.scales[1].end, static_cast<int>(two.points.size()));
  EXPECT_DOUBLE_EQ(two.VoxelOf(two.scales[1].begin), 0.45);
  EXPECT_DOUBLE_EQ(two.VoxelOf(0), 0.15);
  // Keypoints from both scales; the fine ones as before.
  int fine_keypoints = 0, coarse_keypoints = 0;
  for (int k : two.keypoints) (k < two.FinestEnd() ? fine_keypoints : coarse_keypoints)++;
  EXPECT_EQ(fine_keypoints, static_cast<int>(one.keypoints.size()));
  EXPECT_GT(coarse_keypoints, 0);
}

TEST(GeometricFeatures, MatchesPairSamplesOfTheSameScaleNearTheTruth) {
  const Eigen::Isometry3d world_from_a = testing::RoomStation(-2.0, 1.0, 20.0);
  const Eigen::Isometry3d world_from_b = testing::RoomStation(1.0, -1.5, -35.0);
  const Scan a = testing::CastRoomScan(world_from_a, 200, 800, testing::DefaultRoom(), testing::DefaultBlocks(), 0.002, 1);
  const Scan b = testing::CastRoomScan(world_from_b, 200, 800, testing::DefaultRoom(), testing::DefaultBlocks(), 0.002, 2);
  const GeometricFeatures fa = Detect(a, 3.0), fb = Detect(b, 3.0);
  const std::vector<GeometricMatch> matches = MatchGeometric(fa, fb);
  ASSERT_FALSE(matches.empty());
  const Eigen::Isometry3d a_from_b = world_from_a.inverse() * world_from_b;
  int coarse = 0, near_truth = 0;
  for (const GeometricMatch& m : matches) {
    const bool parent_coarse = m.parent >= fa.FinestEnd(), child_coarse = m.child >= fb.FinestEnd();
    ASSERT_EQ(parent_coarse, child_coarse) << "a match across scales";
    coarse += parent_coarse;
    near_truth += (fa.points[m.parent] - a_from_b * fb.points[m.child]).norm() <= 2.0 * fa.VoxelOf(m.parent);
  }
  EXPECT_GT(coarse, 0);
  EXPECT_GT(near_truth, 10) << "of " << matches.size() << " matches";
  // One scale on either side: only fine matches.
  for (const GeometricMatch& m : MatchGeometric(Detect(a, 0.0), fb)) EXPECT_LT(m.child, fb.FinestEnd());
}

}  // namespace
}  // namespace scanreg
