// Registered means verified (issue 33): the checks of core/pipeline/verify_poses.h on scans of a
// simulated room with known poses, and on the real bunny scans from perturbed poses.
#include "core/pipeline/verify_poses.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/io/pose_file.h"
#include "core/pipeline/register_project.h"
#include "core/registration/voxel_filter.h"
#include "tests/registration/synthetic_room.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = 180.0 / M_PI;
constexpr double kNoise = 0.003;



// Four stations in one room, their start poses the truth; `result` as the driver would return it
// (every scan registered to the root s0), with poses the caller then changes.
struct Room {
  std::vector<Scan> scans;
  std::vector<std::vector<Eigen::Vector3d>> samples;
  std::vector<Eigen::Isometry3d> truth;
  ProjectRegistration result;
  ScanOrderChoices choices;
  VerifyOptions options;
};

Room MakeRoom() {
  Room r;
  r.truth = {testing::RoomStation(-3, -1, 0), testing::RoomStation(0, 1, 40), testing::RoomStation(3, -1.5, -70), testing::RoomStation(1, 2.5, 150)};
  r.result.root = 0;
  for (std::size_t i = 0; i < r.truth.size(); ++i) {
    Scan s = testing::CastRoomScan(r.truth[i], 120, 360, testing::DefaultRoom(), testing::DefaultBlocks(), kNoise,
                                   static_cast<unsigned>(i + 1));
    s.name = "s" + std::to_string(i);
    s.world_from_scan = r.truth[i];
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k]) pts.push_back(s.points[k].cast<double>());
    r.samples.push_back(VoxelDownsample(pts, 0.05));
    ScanRegistration reg;
    reg.name = s.name;
    reg.registered = true;
    reg.parent = i == 0 ? -1 : 0;
    reg.world_from_scan = r.truth[i];
    r.result.scans.push_back(reg);
    if (i > 0) {
      io::LinkRecord l;
      l.parent = "s0";
      l.child = s.name;
      l.status = io::LinkStatus::kOk;
      r.result.links.push_back(l);
    }
    r.scans.push_back(std::move(s));
  }
  r.choices.overrides.resize(r.scans.size());
  r.options.cutoff_m = r.options.evidence_m = 0.1;
  r.options.noise_m = kNoise;
  return r;
}

TEST(VerifyPoses, AScanALinkMovedAwayFromItsOverlapsGoesBackToItsStartPose) {
  Room room = MakeRoom();
  room.options.multiview = false;  // the check alone
  room.result.scans[2].world_from_scan = testing::MovedPose(room.truth[2], 50, 1.0, 7);
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(VerifyAgainstStart(room.scans, room.samples, room.choices, room.options, progress, cancel, &room.result).ok());
  ASSERT_TRUE(room.result.consistency.has_value());
  EXPECT_TRUE(room.result.scans[2].world_from_scan.isApprox(room.truth[2], 1e-12));
  EXPECT_EQ(room.result.links[1].status, io::LinkStatus::kFailed);
  EXPECT_NE(room.result.links[1].reason.find("disagrees with its other overlaps"), std::string::npos)
      << room.result.links[1].reason;
  for (int i : {1, 3}) EXPECT_EQ(room.result.links[i - 1].status, io::LinkStatus::kOk);
  // Back at a consistent start pose the scan is verified; the project is no worse than the start.
  for (const ScanRegistration& s : room.result.scans) EXPECT_TRUE(s.registered) << s.name << ": " << s.reason;
  EXPECT_LE(room.result.consistency->result_rms_m, room.result.consistency->start_rms_m);
  EXPECT_FALSE(room.result.consistency->refused);
}

TEST(VerifyPoses, TheMultiViewStepBringsAStrayScanBackWithoutUndoingItsLink) {
  Room room = MakeRoom();
  for (int i = 1; i < 4; ++i) room.scans[i].world_from_scan = testing::MovedPose(room.truth[i], 30, 0.5, 20 + i);  // starts off
  for (int i = 1; i < 4; ++i) room.result.scans[i].world_from_scan = testing::MovedPose(room.truth[i], 15, 0.2, 30 + i);  // pairwise
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(VerifyAgainstStart(room.scans, room.samples, room.choices, room.options, progress, cancel, &room.result).ok());
  ASSERT_TRUE(room.result.consistency.has_value());
  EXPECT_TRUE(room.result.consistency->multiview);
  for (int i = 1; i < 4; ++i) {
    const PoseError e = ComparePoses(room.result.scans[i].world_from_scan, room.truth[i]);
    std::printf("s%d: %.2f mm / %.4f deg from the truth, residual %.2f mm, conditioning %.3f\n", i, 1e3 * e.position_m,
                e.angle_rad * kDeg, 1e3 * room.result.scans[i].consistency_m, room.result.scans[i].conditioning);
    EXPECT_LT(e.position_m, 0.002);
    EXPECT_TRUE(room.result.scans[i].registered) << room.result.scans[i].reason;
    EXPECT_LT(room.result.scans[i].consistency_m, 2 * kNoise);
  }
  EXPECT_LT(room.result.consistency->result_rms_m, 0.5 * room.result.consistency->start_rms_m);
}

TEST(VerifyPoses, AScanWhoseOverlapsDisagreeIsNotCalledRegistered) {
  Room room = MakeRoom();
  room.options.multiview = false;
  // Its start pose and its result agree (no link moved it), and both are 40 mm off.
  room.scans[3].world_from_scan = room.result.scans[3].world_from_scan = testing::MovedPose(room.truth[3], 40, 0.5, 5);
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(VerifyAgainstStart(room.scans, room.samples, room.choices, room.options, progress, cancel, &room.result).ok());
  ASSERT_TRUE(room.result.consistency.has_value());
  EXPECT_FALSE(room.result.scans[3].registered);
  EXPECT_NE(room.result.scans[3].reason.find("its overlaps disagree"), std::string::npos) << room.result.scans[3].reason;
  for (int i : {0, 1, 2}) EXPECT_TRUE(room.result.scans[i].registered) << room.result.scans[i].reason;
}

// The ten bunny scans from bun.conf moved by 5 deg / 5 mm (issue 33's protocol), default options, both
// fine methods: no pair of scans called registered beyond 1 cm / 2 deg of the reference, at least
// 90 % of them within 2 mm / 0.5 deg, and the consistency after no worse than at the start.
TEST(VerifyPoses, BunnyFromFiveDegreesNeverWorseAndNeverWrongWhenRegistered) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::filesystem::path dir = data / "stanford_bunny";
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(dir / "bun.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> reference;
  for (const io::NamedPose& p : *poses) {
    Expected<Scan> s = io::ReadPly(dir / p.scan, progress, cancel);
    ASSERT_TRUE(s.ok()) << s.error().ToString();
    s->name = p.scan.substr(0, p.scan.find('.'));
    s->reference_world_from_scan = p.world_from_scan;
    reference.push_back(std::move(*s));
  }
  for (unsigned seed : {1u, 3u}) {
    std::vector<Scan> scans = reference;
    for (std::size_t i = 0; i < scans.size(); ++i)
      scans[i].world_from_scan = testing::MovedPose(*scans[i].reference_world_from_scan, 5, 5, seed * 100 + static_cast<unsigned>(i));
    for (FineMethod fine : {FineMethod::kDense, FineMethod::kEm}) {
      RegisterOptions o;
      o.from_current_poses = true;  // what `register` does on imported poses
      o.fine = fine;
      Expected<ProjectRegistration> r = RegisterScans(scans, {}, o, progress, cancel);
      ASSERT_TRUE(r.ok()) << r.error().ToString();
      int registered = 0, pairs = 0, within = 0, wrong = 0;
      for (std::size_t i = 0; i < scans.size(); ++i) {
        registered += r->scans[i].registered;
        for (std::size_t j = i + 1; j < scans.size(); ++j) {
          if (!r->scans[i].registered || !r->scans[j].registered) continue;
          const PoseError e = ComparePoses(r->scans[i].world_from_scan.inverse() * r->scans[j].world_from_scan,
                                           scans[i].reference_world_from_scan->inverse() * *scans[j].reference_world_from_scan);
          ++pairs;
          within += e.position_m <= 0.002 && e.angle_rad <= 0.5 / kDeg;
          wrong += e.position_m > 0.01 || e.angle_rad > 2.0 / kDeg;
        }
      }
      ASSERT_TRUE(r->consistency.has_value());
      std::printf("bunny 5 deg / 5 mm, seed %u, --fine %s: %d of 10 registered, %d of %d pairs within 2 mm / 0.5 deg, "
                  "%d beyond 1 cm / 2 deg; consistency %.3f -> %.3f mm\n",
                  seed, FineMethodName(fine), registered, within, pairs, wrong, 1e3 * r->consistency->start_rms_m,
                  1e3 * r->consistency->result_rms_m);
      EXPECT_EQ(wrong, 0);
      EXPECT_GE(within, 0.9 * pairs);
      EXPECT_GE(registered, 7);
      ASSERT_TRUE(r->consistency.has_value());
      EXPECT_LE(r->consistency->result_rms_m, r->consistency->start_rms_m);
    }
  }
}

}  // namespace
}  // namespace scanreg::pipeline
