// The registration evidence a project keeps for reports (optional fields): the confusion matrix
// with the names of its scans, each scan's coarse pose and why a scan is not registered.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/io/project.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

Project ThreeScans(const test::TempDir& dir) {
  Project p;
  for (const char* name : {"a", "b", "c"}) {
    std::ofstream(dir / (std::string(name) + ".ptx")) << "x";
    ProjectScan s;
    s.name = name;
    s.path = dir / (std::string(name) + ".ptx");
    p.scans.push_back(s);
  }
  p.confusion.resize(3, 3);
  p.confusion << 900, 120, 7, 118, 950, 64, 5, 60, 870;
  p.confusion_scans = {"a", "b", "c"};
  p.scans[1].registered = true;
  p.scans[1].coarse_world_from_scan = Eigen::Isometry3d(Eigen::Translation3d(4.01, 0.02, -0.01));
  p.scans[2].unregistered_reason = "link to b failed: no overlap";
  return p;
}

TEST(ProjectRegistrationFields, RoundTrip) {
  test::TempDir dir;
  const Project p = ThreeScans(dir);
  ASSERT_NE(p.CurrentConfusion(), nullptr);
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  Expected<Project> back = LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_NE(back->CurrentConfusion(), nullptr);
  EXPECT_TRUE(*back->CurrentConfusion() == p.confusion);
  EXPECT_EQ(back->confusion_scans, p.confusion_scans);
  ASSERT_TRUE(back->scans[1].coarse_world_from_scan.has_value());
  EXPECT_TRUE(back->scans[1].coarse_world_from_scan->isApprox(*p.scans[1].coarse_world_from_scan, 1e-15));
  EXPECT_FALSE(back->scans[0].coarse_world_from_scan.has_value());
  EXPECT_EQ(back->scans[2].unregistered_reason, "link to b failed: no overlap");
  EXPECT_EQ(ScanPoseState(back->scans[2]), PoseState::kUnregistered);
}

// A scan the registration placed but could not verify stays "not verified" after a save and a
// load, apart from a scan it could not place at all; a registered scan is never "not verified".
TEST(ProjectRegistrationFields, NotVerifiedIsKept) {
  test::TempDir dir;
  Project p = ThreeScans(dir);
  p.scans[0].unverified = true;
  p.scans[0].unregistered_reason = "not verified: placed only by a weak link from b";
  p.scans[1].unverified = true;  // stale: the scan is registered
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  Expected<Project> back = LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_EQ(ScanPoseState(back->scans[0]), PoseState::kNotVerified);
  EXPECT_STREQ(PoseStateName(ScanPoseState(back->scans[0])), "not verified");
  EXPECT_EQ(back->scans[0].unregistered_reason, p.scans[0].unregistered_reason);
  EXPECT_EQ(ScanPoseState(back->scans[1]), PoseState::kRegistered);
  EXPECT_FALSE(back->scans[1].unverified);
  EXPECT_EQ(ScanPoseState(back->scans[2]), PoseState::kUnregistered);
}

TEST(ProjectRegistrationFields, AStaleMatrixIsNeitherUsedNorSaved) {
  test::TempDir dir;
  Project p = ThreeScans(dir);
  std::ofstream(dir / "d.ptx") << "x";
  ProjectScan d;
  d.name = "d";
  d.path = dir / "d.ptx";
  p.scans.push_back(d);  // a scan added after the registration
  EXPECT_EQ(p.CurrentConfusion(), nullptr);
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  EXPECT_EQ(test::ReadBytes(dir / "p.scanreg.json").find("\"confusion\""), std::string::npos);
  Expected<Project> back = LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_EQ(back->CurrentConfusion(), nullptr);
  // Reordered scans: the stored matrix no longer matches them and is ignored, not misread.
  Project q = ThreeScans(dir);
  std::swap(q.scans[0], q.scans[2]);
  EXPECT_EQ(q.CurrentConfusion(), nullptr);
}

TEST(ProjectRegistrationFields, AMalformedMatrixIsAClearError) {
  test::TempDir dir;
  ASSERT_TRUE(SaveProject(ThreeScans(dir), dir / "p.scanreg.json").ok());
  std::string text = test::ReadBytes(dir / "p.scanreg.json");
  const std::size_t at = text.find("870");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 3, "-870");
  std::ofstream(dir / "bad.scanreg.json") << text;
  Expected<Project> bad = LoadProject(dir / "bad.scanreg.json");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("confusion"), std::string::npos) << bad.error().message;
  EXPECT_NE(bad.error().message.find("bad.scanreg.json"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace scanreg::io
