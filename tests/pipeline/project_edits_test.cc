#include "core/pipeline/project_edits.h"

#include <gtest/gtest.h>

namespace scanreg::pipeline {
namespace {

Eigen::Isometry3d Pose(double x, double y, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 0.1);
  return t;
}

io::LinkRecord Link(const io::Project& p, const std::string& parent, const std::string& child) {
  io::LinkRecord l;
  l.parent = parent;
  l.child = child;
  l.status = io::LinkStatus::kOk;
  l.parent_from_child =
      p.scans[p.FindScan(parent)].world_from_scan.inverse() * p.scans[p.FindScan(child)].world_from_scan;
  return l;
}

// s1 (root) -> s2 -> s3, s1 -> s4; s5 unregistered.
io::Project Tree() {
  io::Project p;
  const Eigen::Isometry3d poses[] = {Pose(0, 0, 0), Pose(5, 0, 0.1), Pose(10, 1, 0.2), Pose(0, 6, -0.3), Pose(3, 3, 0)};
  for (int i = 0; i < 5; ++i) {
    io::ProjectScan s;
    s.name = "s" + std::to_string(i + 1);
    s.world_from_scan = poses[i];
    s.registered = i < 4;
    if (s.registered)
      s.coarse_world_from_scan = poses[i];
    else
      s.unregistered_reason = "no link";
    p.scans.push_back(s);
  }
  p.root = "s1";
  p.links = {Link(p, "s1", "s2"), Link(p, "s2", "s3"), Link(p, "s1", "s4")};
  io::LinkRecord failed = Link(p, "s4", "s3");
  failed.status = io::LinkStatus::kFailed;
  p.links.push_back(failed);
  return p;
}

TEST(ApplyPairResult, MovesTheChildAndTheScansRegisteredThroughIt) {
  io::Project p = Tree();
  const io::Project before = p;
  io::LinkRecord link = Link(p, "s4", "s2");
  link.parent_from_child = link.parent_from_child * Pose(0.05, -0.02, 0.01);  // the new result differs
  link.method = "epnp+keypoints";
  ASSERT_TRUE(ApplyPairResult(link, p).ok());
  const Eigen::Isometry3d s2 = p.scans[3].world_from_scan * link.parent_from_child;
  EXPECT_TRUE(p.scans[1].world_from_scan.isApprox(s2, 1e-12));
  // s3 keeps its pose relative to s2; s1, s4 and the unregistered s5 stay.
  const Eigen::Isometry3d rel_before = before.scans[1].world_from_scan.inverse() * before.scans[2].world_from_scan;
  EXPECT_TRUE((p.scans[1].world_from_scan.inverse() * p.scans[2].world_from_scan).isApprox(rel_before, 1e-12));
  for (int i : {0, 3, 4}) EXPECT_TRUE(p.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0));
  EXPECT_FALSE(p.scans[4].registered);
  // The new link replaces s2's tree link; the parent changed, so it is kept as an override.
  int into_s2 = 0;
  for (const io::LinkRecord& l : p.links) into_s2 += l.child == "s2";
  EXPECT_EQ(into_s2, 1);
  EXPECT_EQ(p.links.back().parent, "s4");
  EXPECT_EQ(p.links.back().method, "epnp+keypoints");
  EXPECT_EQ(p.scans[1].parent_override.value_or(""), "s4");
  EXPECT_EQ(p.links.size(), before.links.size());  // the failed attempt s4 -> s3 is kept
  // The moved scans' coarse poses described the replaced automatic run; the others keep theirs.
  EXPECT_FALSE(p.scans[1].coarse_world_from_scan.has_value());
  EXPECT_FALSE(p.scans[2].coarse_world_from_scan.has_value());
  EXPECT_TRUE(p.scans[0].coarse_world_from_scan.has_value());
  EXPECT_TRUE(p.scans[3].coarse_world_from_scan.has_value());
}

TEST(ApplyPairResult, SameParentReplacesTheLinkWithoutAnOverride) {
  io::Project p = Tree();
  io::LinkRecord link = Link(p, "s1", "s2");
  link.status = io::LinkStatus::kWeak;
  link.parent_from_child.translation().x() += 0.1;
  ASSERT_TRUE(ApplyPairResult(link, p).ok());
  EXPECT_FALSE(p.scans[1].parent_override.has_value());
  EXPECT_NEAR(p.scans[1].world_from_scan.translation().x(), 5.1, 1e-12);
  EXPECT_TRUE(p.links.back().user_accepted);  // a weak result the user chose is accepted
}

TEST(ApplyPairResult, RegistersAnUnregisteredChild) {
  io::Project p = Tree();
  io::LinkRecord link = Link(p, "s4", "s5");
  ASSERT_TRUE(ApplyPairResult(link, p).ok());
  EXPECT_TRUE(p.scans[4].registered);
  EXPECT_TRUE(p.scans[4].world_from_scan.isApprox(Pose(3, 3, 0), 1e-12));
  EXPECT_TRUE(p.scans[4].unregistered_reason.empty());
}

TEST(ApplyPairResult, RefusesCyclesFailedLinksAndUnregisteredParents) {
  io::Project p = Tree();
  const io::Project before = p;
  Status cycle = ApplyPairResult(Link(p, "s3", "s2"), p);  // s3 is registered through s2
  ASSERT_FALSE(cycle.ok());
  EXPECT_NE(cycle.error().message.find("cycle"), std::string::npos) << cycle.error().message;
  io::LinkRecord failed = Link(p, "s4", "s2");
  failed.status = io::LinkStatus::kFailed;
  failed.reason = "overlap too small";
  Status f = ApplyPairResult(failed, p);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.error().message.find("overlap too small"), std::string::npos);
  Status unregistered = ApplyPairResult(Link(p, "s5", "s2"), p);
  ASSERT_FALSE(unregistered.ok());
  EXPECT_NE(unregistered.error().message.find("'s5' is not registered"), std::string::npos);
  EXPECT_FALSE(ApplyPairResult(Link(p, "s1", "s1"), p).ok());
  // A refused result changes nothing.
  for (std::size_t i = 0; i < p.scans.size(); ++i)
    EXPECT_TRUE(p.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0));
  EXPECT_EQ(p.links.size(), before.links.size());
}

}  // namespace
}  // namespace scanreg::pipeline

namespace scanreg::pipeline {
namespace {

TEST(SetScanPose, MovesTheScanAndItsDependentsAndMarksItManual) {
  io::Project p = Tree();
  const io::Project before = p;
  const Eigen::Isometry3d target = Pose(5.5, 0.3, 0.15);
  ASSERT_TRUE(SetScanPose("s2", target, /*move_dependents=*/true, p).ok());
  EXPECT_TRUE(p.scans[1].world_from_scan.isApprox(target, 1e-12));
  EXPECT_TRUE(p.scans[1].manual_pose);
  EXPECT_TRUE(p.scans[1].registered);
  // s3 hangs below s2: it keeps its pose relative to s2; s1, s4 and s5 stay.
  const Eigen::Isometry3d rel_before = before.scans[1].world_from_scan.inverse() * before.scans[2].world_from_scan;
  EXPECT_TRUE((p.scans[1].world_from_scan.inverse() * p.scans[2].world_from_scan).isApprox(rel_before, 1e-12));
  EXPECT_FALSE(p.scans[2].manual_pose);
  for (int i : {0, 3, 4}) EXPECT_TRUE(p.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0));
  EXPECT_FALSE(p.scans[1].coarse_world_from_scan.has_value());
  EXPECT_TRUE(p.scans[0].coarse_world_from_scan.has_value());
}

TEST(SetScanPose, WithoutDependentsOnlyTheScanMovesAndAnUnregisteredScanBecomesRegistered) {
  io::Project p = Tree();
  const io::Project before = p;
  ASSERT_TRUE(SetScanPose("s2", Pose(6, 0, 0), /*move_dependents=*/false, p).ok());
  EXPECT_TRUE(p.scans[2].world_from_scan.isApprox(before.scans[2].world_from_scan, 0.0));
  ASSERT_TRUE(SetScanPose("s5", Pose(2, 2, 1.0), true, p).ok());
  EXPECT_TRUE(p.scans[4].registered);
  EXPECT_TRUE(p.scans[4].manual_pose);
  EXPECT_TRUE(p.scans[4].unregistered_reason.empty());
  EXPECT_TRUE(p.scans[4].world_from_scan.isApprox(Pose(2, 2, 1.0), 1e-12));
}

TEST(SetScanPose, RefusesUnknownScansAndNonRigidOrNonFinitePoses) {
  io::Project p = Tree();
  const io::Project before = p;
  EXPECT_FALSE(SetScanPose("nope", Pose(0, 0, 0), true, p).ok());
  Eigen::Isometry3d scaled = Pose(1, 1, 0);
  scaled.linear() *= 1.01;
  Status s = SetScanPose("s2", scaled, true, p);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("not a rigid motion"), std::string::npos) << s.error().message;
  Eigen::Isometry3d nan = Pose(1, 1, 0);
  nan.translation().x() = std::nan("");
  EXPECT_FALSE(SetScanPose("s2", nan, true, p).ok());
  for (std::size_t i = 0; i < p.scans.size(); ++i) {
    EXPECT_TRUE(p.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan, 0.0));
    EXPECT_FALSE(p.scans[i].manual_pose);
  }
}

TEST(ApplyPairResult, ALinkReplacesAManualPose) {
  io::Project p = Tree();
  ASSERT_TRUE(SetScanPose("s4", Pose(0, 6.2, -0.3), true, p).ok());
  ASSERT_TRUE(p.scans[3].manual_pose);
  ASSERT_TRUE(ApplyPairResult(Link(p, "s1", "s4"), p).ok());
  EXPECT_FALSE(p.scans[3].manual_pose);
}

// The reasons a scan was left out name other scans: they follow a rename (whole names only: s1 is
// not in s10), say so when the scan they name is removed, and stop calling a scan "not verified"
// once the user has placed it (issue 33).
TEST(ScanReasons, FollowRenamesRemovalsAndTheUsersPlacement) {
  io::Project p = Tree();
  io::ProjectScan s10 = p.scans[4];
  s10.name = "s10";
  s10.unregistered_reason = "link to s1 failed: loop s1-s10-s2 does not close";
  p.scans.push_back(s10);
  p.scans[4].unverified = true;
  p.scans[4].unregistered_reason = "not verified: placed only by a weak link from s1 (small overlap)";
  p.links[3].reason = "loop s4-s3-s1 does not close; s10 was checked";
  ASSERT_TRUE(RenameScan("s1", "north", p).ok());
  EXPECT_EQ(p.scans[4].unregistered_reason, "not verified: placed only by a weak link from north (small overlap)");
  EXPECT_EQ(p.scans[5].unregistered_reason, "link to north failed: loop north-s10-s2 does not close");
  EXPECT_EQ(p.links[3].reason, "loop s4-s3-north does not close; s10 was checked");

  // s3 not verified, s5 placed through it: the user places s3 by a pair result.
  p.scans[2].registered = false;
  p.scans[2].unverified = true;
  p.scans[2].unregistered_reason = "not verified: placed only by a weak link from s2 (small overlap)";
  p.scans[4].unregistered_reason = "not verified: placed through s3, which is not verified";
  ASSERT_TRUE(ApplyPairResult(Link(p, "s2", "s3"), p).ok());
  EXPECT_TRUE(p.scans[2].registered);
  EXPECT_FALSE(p.scans[4].registered);
  EXPECT_EQ(p.scans[4].unregistered_reason.find("which is not verified"), std::string::npos) << p.scans[4].unregistered_reason;
  EXPECT_NE(p.scans[4].unregistered_reason.find("register again to place s5"), std::string::npos)
      << p.scans[4].unregistered_reason;

  // s2 removed: the reason of s10 that named it says it went.
  ASSERT_TRUE(RemoveScan("s2", p).ok());
  const io::ProjectScan& left = p.scans[p.FindScan("s10")];
  EXPECT_NE(left.unregistered_reason.find("s2, which was removed"), std::string::npos) << left.unregistered_reason;
}

}  // namespace
}  // namespace scanreg::pipeline
