// Issue 33's protocol on real multi-view sets beyond the bunny (tests/support/real_sets.h), with
// default options from the reference moved by 5 deg / 5 mm per scan (imported poses) and from
// identity (no poses).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/geometry/transform.h"
#include "core/pipeline/register_project.h"
#include "tests/registration/synthetic_room.h"
#include "tests/support/real_sets.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;

PoseError PairError(const test::RealSet& set, const std::vector<Eigen::Isometry3d>& world, std::size_t i, std::size_t j) {
  return ComparePoses(world[i].inverse() * world[j], set.scans[i].reference_world_from_scan->inverse() *
                                                         *set.scans[j].reference_world_from_scan);
}

struct Trust {
  int registered = 0, pairs = 0, within = 0, wrong = 0;
  int wrong_any_seed = 0;  // FromImportedPoses: registered pairs beyond "wrong", over every seed
};

// From 5 deg / 5 mm starts (two seeds), what `register` does on imported poses: refinement never
// leaves the project less consistent than its start, at least one scan besides the root is placed,
// and every scan left out says why. Returns the pairs' figures of the last seed.
Trust FromImportedPoses(const test::RealSet& set) {
  const std::size_t n = set.scans.size();
  NullProgress progress;
  CancelToken cancel;
  Trust t;
  int wrong_any_seed = 0;
  for (unsigned seed : {1u, 2u}) {
    t = {};
    std::vector<Scan> scans = set.scans;
    std::vector<Eigen::Isometry3d> start;
    for (std::size_t i = 0; i < n; ++i) {
      scans[i].world_from_scan =
          testing::MovedPose(*scans[i].reference_world_from_scan, 5, 5, seed * 100 + static_cast<unsigned>(i));
      start.push_back(scans[i].world_from_scan);
    }
    RegisterOptions o;
    o.from_current_poses = true;  // what `register` does on imported poses
    Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
    EXPECT_TRUE(r.ok()) << r.error().ToString();
    if (!r.ok() || !r->consistency.has_value()) {
      ADD_FAILURE() << set.name << ": no consistency figure";
      return t;
    }
    std::vector<Eigen::Isometry3d> world;
    for (const ScanRegistration& s : r->scans) world.push_back(s.world_from_scan);
    int farther = 0;
    for (std::size_t i = 0; i < n; ++i) {
      t.registered += r->scans[i].registered;
      if (!r->scans[i].registered) {
        EXPECT_FALSE(r->scans[i].reason.empty()) << scans[i].name;
      }
      for (std::size_t j = i + 1; j < n; ++j) {
        if (!r->scans[i].registered || !r->scans[j].registered) continue;
        const PoseError before = PairError(set, start, i, j), after = PairError(set, world, i, j);
        ++t.pairs;
        t.within += after.position_m <= set.WithinM(i, j) && after.angle_rad * kDeg <= set.within_deg;
        t.wrong += after.position_m > set.wrong_m || after.angle_rad * kDeg > set.wrong_deg;
        const bool got_worse = after.position_m > before.position_m || after.angle_rad > before.angle_rad;
        farther += got_worse;
        std::printf("  %s-%s: %.1f mm %.2f deg from the reference (start %.1f mm %.2f deg)%s\n", scans[i].name.c_str(),
                    scans[j].name.c_str(), 1e3 * after.position_m, after.angle_rad * kDeg, 1e3 * before.position_m,
                    before.angle_rad * kDeg, got_worse ? "  farther" : "");
      }
    }
    std::printf("%s from 5 deg / 5 mm, seed %u: %d of %zu registered, %d of %d pairs farther from the reference than "
                "at the start, %d within %.0f mm (+%.0f a step) / %.1f deg, %d beyond %.0f mm / %.0f deg; consistency %.2f -> %.2f mm\n",
                set.name.c_str(), seed, t.registered, n, farther, t.pairs, t.within, 1e3 * set.within_m, 1e3 * set.within_m_per_step, set.within_deg,
                t.wrong, 1e3 * set.wrong_m, set.wrong_deg, 1e3 * r->consistency->start_rms_m,
                1e3 * r->consistency->result_rms_m);
    EXPECT_GE(t.registered, 2) << set.name;  // the root and at least one scan placed by the refinement
    EXPECT_LE(r->consistency->result_rms_m, r->consistency->start_rms_m) << set.name;
    wrong_any_seed += t.wrong;
  }
  t.wrong_any_seed = wrong_any_seed;
  return t;
}

// With no poses (every scan at the identity) and default options: no pair of registered scans beyond
// the set's "wrong" tolerance, and every scan left out says why.
Trust FromNoPoses(const test::RealSet& set) {
  const std::size_t n = set.scans.size();
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> scans = set.scans;
  for (Scan& s : scans) s.world_from_scan = Eigen::Isometry3d::Identity();
  Expected<ProjectRegistration> r = RegisterScans(scans, {}, RegisterOptions(), progress, cancel);
  EXPECT_TRUE(r.ok()) << r.error().ToString();
  Trust t;
  if (!r.ok()) return t;
  std::vector<Eigen::Isometry3d> world;
  for (const ScanRegistration& s : r->scans) world.push_back(s.world_from_scan);
  for (std::size_t i = 0; i < n; ++i) {
    t.registered += r->scans[i].registered;
    if (!r->scans[i].registered) {
      EXPECT_FALSE(r->scans[i].reason.empty()) << scans[i].name;
    }
    for (std::size_t j = i + 1; j < n; ++j) {
      if (!r->scans[i].registered || !r->scans[j].registered) continue;
      const PoseError e = PairError(set, world, i, j);
      ++t.pairs;
      t.within += e.position_m <= set.WithinM(i, j) && e.angle_rad * kDeg <= set.within_deg;
      t.wrong += e.position_m > set.wrong_m || e.angle_rad * kDeg > set.wrong_deg;
      std::printf("  %s-%s: %.1f mm %.2f deg from the reference\n", scans[i].name.c_str(), scans[j].name.c_str(),
                  1e3 * e.position_m, e.angle_rad * kDeg);
    }
  }
  std::printf("%s from identity: %d of %zu registered, %d of %d pairs within %.0f mm (+%.0f a step) / %.1f deg, %d beyond %.0f mm / "
              "%.0f deg\n",
              set.name.c_str(), t.registered, n, t.within, t.pairs, 1e3 * set.within_m, 1e3 * set.within_m_per_step,
              set.within_deg, t.wrong,
              1e3 * set.wrong_m, set.wrong_deg);
  EXPECT_EQ(t.wrong, 0) << set.name;
  return t;
}

// Twelve Kinect keyframes circling a cabinet: a floor and a few box faces, depth distorted by
// centimetres, reference poses good to a few centimetres only (7 of the 11 consecutive pairs put over
// 5 % of one frame in the other's free space at the reference), so they judge gross errors, not
// millimetres. What must hold: refinement never leaves the project less consistent than its start,
// every scan left unregistered says why, and from identity no scan is placed grossly wrong. The
// pairs' errors against the reference are printed here and in the bench's trust section (today
// 16-104 mm from starts 9-38 mm off: the reference cannot tell whose error that is).
TEST(RealSets, TumCabinetRefinementIsMoreConsistentAndSaysWhyAScanIsLeftOut) {
  SCANREG_REQUIRE_REALDATA(data);
  Expected<test::RealSet> set = test::LoadTumCabinet(data);
  ASSERT_TRUE(set.ok()) << set.error().ToString();
  FromImportedPoses(*set);
  FromNoPoses(*set);
}

// Mobile lidar: four consecutive KITTI Velodyne sweeps 0.86 m apart, read from PLY as a user imports
// them (not tuned on: added after the product's thresholds). Besides the protocol above: from no
// poses every scan is registered and 90 % of the pairs land within the reference's own precision
// (0.13-0.17 m a frame along the way the car drives, measured by an independent ICP, + 2 x the
// lidar's noise). Today all six pairs do, 0.13-0.45 m from the GPS/INS poses where that ICP put them.
TEST(RealSets, KittiVelodyneSweepsRegisterWithinTheReferencesPrecision) {
  SCANREG_REQUIRE_REALDATA(data);
  Expected<test::RealSet> set = test::LoadKittiVelodyne(data);
  ASSERT_TRUE(set.ok()) << set.error().ToString();
  const Trust imported = FromImportedPoses(*set);
  EXPECT_EQ(imported.wrong_any_seed, 0);
  EXPECT_EQ(imported.registered, static_cast<int>(set->scans.size()));
  EXPECT_GE(imported.within, (9 * imported.pairs + 9) / 10);
  const Trust t = FromNoPoses(*set);
  EXPECT_EQ(t.registered, static_cast<int>(set->scans.size()));
  EXPECT_GE(t.within, (9 * t.pairs + 9) / 10);
}

// Three stop-and-go scans of a tilting 2D laser on a robot in a corridor (3dtk_robot_scans), the
// reference its authors' own registration (about
// 5 cm / 1 deg). The protocol above, and from the imported poses too no pair of registered scans
// beyond 30 cm / 3 deg. (Before a loop that does not close also failed the weak links on its path,
// seed 1 kept a weak link, RMS 3 x the noise, that put a scan 3.5 deg off, "registered".)
TEST(RealSets, RobotCorridorScansAreNeverRegisteredWrong) {
  SCANREG_REQUIRE_REALDATA(data);
  Expected<test::RealSet> set = test::Load3dtkCorridor(data);
  ASSERT_TRUE(set.ok()) << set.error().ToString();
  const Trust imported = FromImportedPoses(*set);
  EXPECT_EQ(imported.wrong_any_seed, 0);
  FromNoPoses(*set);
}

}  // namespace
}  // namespace scanreg::pipeline
