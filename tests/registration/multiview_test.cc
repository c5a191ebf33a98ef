// The consistency measure and the multi-view fine step (issue 33) on scans of a simulated room with
// known poses, and a plane that leaves directions free.
#include "core/registration/multiview.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/geometry/transform.h"
#include "core/registration/voxel_filter.h"
#include "tests/registration/synthetic_room.h"

namespace scanreg {
namespace {

constexpr double kDeg = 180.0 / M_PI;
constexpr double kNoise = 0.003;  // range noise of the simulated scanner, metres


struct Views {
  std::vector<ViewSurface> surfaces;
  std::vector<const ViewSurface*> pointers;
  Poses truth;
};

Views RoomViews() {
  Views v;
  v.truth = {testing::RoomStation(-3, -1, 0), testing::RoomStation(0, 1, 40), testing::RoomStation(3, -1.5, -70), testing::RoomStation(1, 2.5, 150)};
  v.surfaces.resize(v.truth.size());
  for (std::size_t i = 0; i < v.truth.size(); ++i) {
    const Scan s = testing::CastRoomScan(v.truth[i], 120, 360, testing::DefaultRoom(), testing::DefaultBlocks(), kNoise,
                                         static_cast<unsigned>(i + 1));
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k]) pts.push_back(s.points[k].cast<double>());
    v.surfaces[i] = MakeViewSurface(VoxelDownsample(pts, 0.05));
  }
  for (const ViewSurface& s : v.surfaces) v.pointers.push_back(&s);
  return v;
}


TEST(Consistency, AMisplacedScanIsTheLeastConsistentAndTheTruthIsNearTheNoise) {
  const Views v = RoomViews();
  Poses moved = v.truth;
  moved[2] = testing::MovedPose(v.truth[2], 40, 0.5, 3);
  const std::vector<bool> all(4, true);
  const auto pairs = OverlappingPairs(v.pointers, {v.truth, moved}, all, 0.1, 0.05);
  ASSERT_EQ(pairs.size(), 6u);  // every station of one room sees the others
  const std::vector<Consistency> c = MeasureConsistency(v.pointers, {v.truth, moved}, pairs, 0.1, 0.025);
  ASSERT_EQ(c.size(), 2u);
  std::printf("room: robust RMS %.2f mm at the truth, %.2f mm with one scan 40 mm / 0.5 deg off (its share %.2f mm)\n",
              1e3 * c[0].rms_m, 1e3 * c[1].rms_m, 1e3 * c[1].scan_rms_m[2]);
  // Compared on the same samples, the misplaced pose is the less consistent (each pose set also
  // pays for the samples that meet only at the other: borders, occlusions).
  EXPECT_GT(c[1].rms_m, 1.5 * c[0].rms_m);
  // Measured alone, the truth is near the noise: two noisy surfaces, sampled at 5 cm.
  const Consistency truth = MeasureConsistency(v.pointers, {v.truth}, pairs, 0.1, 0.025)[0];
  std::printf("room at the truth alone: %.2f mm\n", 1e3 * truth.rms_m);
  EXPECT_LT(truth.rms_m, 1.5 * kNoise);
  for (int i : {0, 1, 3}) EXPECT_GT(c[1].scan_rms_m[2], c[1].scan_rms_m[i]);
  EXPECT_EQ(c[0].samples, c[1].samples);  // the same samples for both pose sets
}

TEST(MultiView, AllScansAtOnceReturnToTheTruthFromCentimetres) {
  const Views v = RoomViews();
  Poses start = v.truth;
  for (int i = 1; i < 4; ++i) start[i] = testing::MovedPose(v.truth[i], 30, 1.0, 10 + i);
  const std::vector<bool> all(4, true);
  const auto pairs = OverlappingPairs(v.pointers, {start}, all, 0.1, 0.05);
  std::vector<bool> fixed = {true, false, false, false};
  MultiViewOptions o;
  o.cutoff_m = 0.15;
  o.floor_m = 3 * kNoise;
  CancelToken cancel;
  Expected<MultiViewResult> r = AlignMultiView(v.pointers, start, pairs, fixed, o, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  EXPECT_TRUE(r->world[0].isApprox(v.truth[0], 1e-12));  // the datum stays
  for (int i = 1; i < 4; ++i) {
    const PoseError e = ComparePoses(r->world[i], v.truth[i]);
    const PoseError e0 = ComparePoses(start[i], v.truth[i]);
    std::printf("view %d: %.1f mm / %.3f deg -> %.2f mm / %.4f deg, conditioning %.3f\n", i, 1e3 * e0.position_m,
                e0.angle_rad * kDeg, 1e3 * e.position_m, e.angle_rad * kDeg, r->conditioning[i]);
    EXPECT_LT(e.position_m, 0.002);
    EXPECT_LT(e.angle_rad, 0.05 / kDeg);
    EXPECT_GT(r->conditioning[i], 1e-3);  // a room constrains every direction
  }
  const std::vector<Consistency> c = MeasureConsistency(v.pointers, {start, r->world}, pairs, 0.1, 0.025);
  EXPECT_LT(c[1].rms_m, 0.5 * c[0].rms_m);
}

TEST(MultiView, AFlatFloorLeavesDirectionsFreeAndTheConditioningSaysSo) {
  std::vector<Eigen::Vector3d> floor;
  for (int x = 0; x < 60; ++x)
    for (int y = 0; y < 60; ++y) floor.emplace_back(0.05 * x, 0.05 * y, 0.0);
  std::vector<ViewSurface> s(2);
  s[0] = MakeViewSurface(floor);
  s[1] = MakeViewSurface(floor);
  const std::vector<const ViewSurface*> views = {&s[0], &s[1]};
  Poses start(2, Eigen::Isometry3d::Identity());
  start[1].translation() = Eigen::Vector3d(0.01, 0.02, 0.005);
  MultiViewOptions o;
  o.cutoff_m = 0.05;
  CancelToken cancel;
  Expected<MultiViewResult> r = AlignMultiView(views, start, {{0, 1}}, {true, false}, o, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  EXPECT_NEAR(r->world[1].translation().z(), 0.0, 1e-4);  // the constrained direction is found
  EXPECT_LT(r->conditioning[1], 1e-6);                     // the others are free
  // Without a fixed view there is no datum.
  EXPECT_FALSE(AlignMultiView(views, start, {{0, 1}}, {false, false}, o, cancel).ok());
}

}  // namespace
}  // namespace scanreg
