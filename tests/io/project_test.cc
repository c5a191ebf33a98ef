#include "core/io/project.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

void Touch(const std::filesystem::path& p) { std::ofstream(p) << "x"; }

Project TwoScanProject(const test::TempDir& dir) {
  std::filesystem::create_directories(dir / "scans");
  Touch(dir / "scans" / "a.ptx");
  Touch(dir / "scans" / "b.ptx");
  Project p;
  ProjectScan a, b;
  a.name = "a";
  a.path = dir / "scans" / "a.ptx";
  a.registered = true;
  a.manual_pose = true;
  b.name = "b";
  b.path = dir / "scans" / "b.ptx";
  b.world_from_scan.translation() << 500000.123456, 5800000.654321, 12.5;  // UTM-sized, must keep sub-mm
  b.world_from_scan.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.reference_world_from_scan = b.world_from_scan;
  b.parent_override = "a";
  p.scans = {a, b};
  LinkRecord link;
  link.parent = "a";
  link.child = "b";
  link.status = LinkStatus::kWeak;
  link.reason = "only 9 inliers";
  link.ransac_inliers = 9;
  link.rms_m = 0.0123;
  p.links.push_back(link);
  p.root = "a";
  p.settings["coarse"] = "3d";
  return p;
}

TEST(ProjectTest, RoundTripKeepsEverythingWithRelativePaths) {
  test::TempDir dir;
  const Project p = TwoScanProject(dir);
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  std::ifstream in(dir / "p.scanreg.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"scans/a.ptx\""), std::string::npos) << "paths are stored relative to the project";
  EXPECT_EQ(text.find(dir.path().string()), std::string::npos);

  Expected<Project> q = LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(q.ok()) << q.error().ToString();
  ASSERT_EQ(q->scans.size(), 2u);
  EXPECT_EQ(q->scans[1].path, dir / "scans" / "b.ptx");
  EXPECT_LT((q->scans[1].world_from_scan.translation() - p.scans[1].world_from_scan.translation()).norm(), 1e-7);
  EXPECT_TRUE(q->scans[1].world_from_scan.linear().isApprox(p.scans[1].world_from_scan.linear(), 1e-12));
  ASSERT_TRUE(q->scans[1].reference_world_from_scan.has_value());
  EXPECT_EQ(q->scans[1].parent_override.value_or(""), "a");
  EXPECT_TRUE(q->scans[0].registered);
  EXPECT_FALSE(q->scans[1].registered);
  EXPECT_TRUE(q->scans[0].manual_pose);
  EXPECT_FALSE(q->scans[1].manual_pose);
  ASSERT_EQ(q->links.size(), 1u);
  EXPECT_EQ(q->links[0].status, LinkStatus::kWeak);
  EXPECT_EQ(q->links[0].reason, "only 9 inliers");
  EXPECT_EQ(q->links[0].ransac_inliers, 9);
  EXPECT_DOUBLE_EQ(q->links[0].rms_m, 0.0123);
  EXPECT_EQ(q->root.value_or(""), "a");
  EXPECT_EQ(q->settings.at("coarse"), "3d");
}

// A project whose scan file moved is still read (so that it can be relinked: issue 14); loading the
// scans' points names the missing file (pipeline::LoadProjectScans, tests/pipeline).
TEST(ProjectTest, AMissingScanFileStillReadsTheProject) {
  test::TempDir dir;
  ASSERT_TRUE(SaveProject(TwoScanProject(dir), dir / "p.scanreg.json").ok());
  std::filesystem::remove(dir / "scans" / "b.ptx");
  Expected<Project> q = LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(q.ok()) << q.error().message;
  ASSERT_EQ(q->scans.size(), 2u);
  EXPECT_EQ(q->scans[1].path, std::filesystem::absolute(dir / "scans" / "b.ptx").lexically_normal());
}

// A root that names no scan is refused when the project is read (it used to be shown as the root).
TEST(ProjectTest, ARootOrALinkThatNamesNoScanIsAClearError) {
  test::TempDir dir;
  Project p = TwoScanProject(dir);
  p.root = "a";
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  std::ifstream in(dir / "p.scanreg.json");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find("\"root\": \"a\"");
  ASSERT_NE(at, std::string::npos) << text.substr(0, 400);
  text.replace(at, std::string("\"root\": \"a\"").size(), "\"root\": \"ghost\"");
  std::ofstream(dir / "q.scanreg.json") << text;
  Expected<Project> q = LoadProject(dir / "q.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_NE(q.error().message.find("'ghost' is not a scan"), std::string::npos) << q.error().message;
  // The same for a link to a scan the project does not have.
  Project linked = TwoScanProject(dir);
  LinkRecord l;
  l.parent = "a";
  l.child = "ghost";
  linked.links.push_back(l);
  ASSERT_TRUE(SaveProject(linked, dir / "r.scanreg.json").ok());
  Expected<Project> r = LoadProject(dir / "r.scanreg.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'ghost' is not a scan"), std::string::npos) << r.error().message;
}

// A whole number out of range was wrapped by the JSON library (2^40 read as scan 0 of the file).
TEST(ProjectTest, ACountOutOfRangeIsAClearError) {
  test::TempDir dir;
  Project p = TwoScanProject(dir);
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  std::ifstream in(dir / "p.scanreg.json");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string field = "\"index_in_file\": 0";
  ASSERT_NE(text.find(field), std::string::npos) << text.substr(0, 400);
  for (const std::string bad : {"1099511627776", "-1", "1.5", "\"0\""}) {
    std::string changed = text;
    changed.replace(changed.find(field), field.size(), "\"index_in_file\": " + bad);
    std::ofstream(dir / "q.scanreg.json") << changed;
    Expected<Project> q = LoadProject(dir / "q.scanreg.json");
    ASSERT_FALSE(q.ok()) << bad;
    EXPECT_NE(q.error().message.find("index_in_file"), std::string::npos) << q.error().message;
  }
}

TEST(ProjectTest, UnknownSchemaVersionAndGarbageAreClearErrors) {
  test::TempDir dir;
  std::ofstream(dir / "future.scanreg.json") << R"({"schema_version": 99, "scans": []})";
  Expected<Project> q = LoadProject(dir / "future.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_EQ(q.error().code, ErrorCode::kUnsupported);
  EXPECT_NE(q.error().message.find("99"), std::string::npos);

  std::ofstream(dir / "garbage.scanreg.json") << "{ not json";
  q = LoadProject(dir / "garbage.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_EQ(q.error().code, ErrorCode::kParseError);

  EXPECT_EQ(LoadProject(dir / "absent.scanreg.json").error().code, ErrorCode::kNotFound);

  // What crashed or blocked in the fuzz run: a number beyond double, a directory, a FIFO.
  std::ofstream(dir / "huge.scanreg.json")
      << R"({"schema_version": 1, "scans": [{"name": "a", "index_in_file": 1e309}]})";
  q = LoadProject(dir / "huge.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_EQ(q.error().code, ErrorCode::kParseError);
  std::filesystem::create_directory(dir / "dir.scanreg.json");
  q = LoadProject(dir / "dir.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_NE(q.error().message.find("not a regular file"), std::string::npos) << q.error().message;
  ASSERT_EQ(::mkfifo((dir / "fifo.scanreg.json").c_str(), 0600), 0);
  q = LoadProject(dir / "fifo.scanreg.json");  // returns at once: never opened for reading
  ASSERT_FALSE(q.ok());
  EXPECT_NE(q.error().message.find("not a regular file"), std::string::npos) << q.error().message;
}

TEST(ProjectTest, NonRigidPoseAndDuplicateNamesAreRejected) {
  test::TempDir dir;
  Touch(dir / "a.ptx");
  std::ofstream(dir / "shear.scanreg.json")
      << R"({"schema_version":1,"scans":[{"name":"a","path":"a.ptx","world_from_scan":[1,0.5,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]})";
  Expected<Project> q = LoadProject(dir / "shear.scanreg.json");
  ASSERT_FALSE(q.ok());
  EXPECT_NE(q.error().message.find("rigid"), std::string::npos);
  std::ofstream(dir / "dup.scanreg.json")
      << R"({"schema_version":1,"scans":[{"name":"a","path":"a.ptx"},{"name":"a","path":"a.ptx"}]})";
  EXPECT_FALSE(LoadProject(dir / "dup.scanreg.json").ok());
}

TEST(ProjectTest, SaveIsAtomicAndLeavesNoTemporaryFiles) {
  test::TempDir dir;
  const Project p = TwoScanProject(dir);
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  ASSERT_TRUE(SaveProject(p, dir / "p.scanreg.json").ok());
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
  // Saving into a folder that does not exist fails without creating anything.
  EXPECT_FALSE(SaveProject(p, dir / "missing" / "p.scanreg.json").ok());
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
}

}  // namespace
}  // namespace scanreg::io
