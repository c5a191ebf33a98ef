// Creating a project from scan files and adding scans to it (the GUI's New project / Add scans):
// unique names, poses from the files, the project unchanged on error.
#include <gtest/gtest.h>

#include "core/io/pose_csv.h"
#include "core/io/ptx.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_edits.h"
#include "core/pipeline/project_scans.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

// A small organized scan: a 10 x 20 grid on a plane 5 m in front of the scanner, every third cell empty.
Scan PlaneScan(const std::string& name, double x) {
  Scan scan(name, 10, 20);
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c)
      if ((r * scan.cols + c) % 3 != 0) scan.Set(r, c, Eigen::Vector3f(5.0f, 0.1f * c, 0.1f * r), 0.5f);
  scan.world_from_scan.translation() = Eigen::Vector3d(x, 0, 0);
  return scan;
}

std::filesystem::path WritePtxFile(const test::TempDir& dir, const std::string& file, const std::vector<Scan>& scans) {
  NullProgress progress;
  const std::filesystem::path path = dir / file;
  EXPECT_TRUE(io::WritePtx(path, scans, progress, CancelToken()).ok());
  return path;
}

TEST(AppendScanFiles, NamesScansUniquelyAndKeepsTheirPoses) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  // PTX names scans by file: "ab_1", "ab_2"; then a file whose one scan is "ab_1" again.
  const auto a2 = WritePtxFile(dir, "ab_1.ptx", {PlaneScan("a", 3.0)});
  io::Project project;
  NullProgress progress;
  const Status first = AppendScanFiles(project, {ab}, progress, CancelToken());
  ASSERT_TRUE(first.ok()) << first.error().message;
  const Status second = AppendScanFiles(project, {a2}, progress, CancelToken());
  ASSERT_TRUE(second.ok()) << second.error().message;
  ASSERT_EQ(project.scans.size(), 3u);
  EXPECT_EQ(project.scans[0].name, "ab_1");
  EXPECT_EQ(project.scans[1].name, "ab_2");
  EXPECT_EQ(project.scans[2].name, "ab_1_2");
  EXPECT_EQ(project.scans[1].index_in_file, 1);
  // The appended scan reads back named as in the project, with its file's points.
  auto read = LoadProjectScans(project, progress, CancelToken(), {2});
  ASSERT_TRUE(read.ok()) << read.error().message;
  ASSERT_EQ(read->size(), 1u);
  EXPECT_EQ((*read)[0].name, "ab_1_2");
  EXPECT_EQ((*read)[0].CountValid(), PlaneScan("a", 0).CountValid());
  EXPECT_NEAR(project.scans[2].world_from_scan.translation().x(), 3.0, 1e-9);
  EXPECT_NEAR(project.scans[1].world_from_scan.translation().x(), 2.0, 1e-9);
}

// A tilted scan whose file carries its pose (a compensator's pitch and roll): the project keeps
// that pose's vertical in the scan's frame, through a save and a registration's new pose.
TEST(AppendScanFiles, AFilesPoseGivesTheScansVertical) {
  test::TempDir dir;
  Scan tilted = PlaneScan("t", 1.0);
  tilted.world_from_scan.linear() =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const auto file = WritePtxFile(dir, "t.ptx", {tilted, PlaneScan("u", 2.0)});
  io::Project project;
  NullProgress progress;
  ASSERT_TRUE(AppendScanFiles(project, {file}, progress, CancelToken()).ok());
  ASSERT_TRUE(project.scans[0].file_up.has_value());
  const Eigen::Vector3d expect = tilted.world_from_scan.linear().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_LT((*project.scans[0].file_up - expect).norm(), 1e-9);
  EXPECT_NEAR(std::acos(project.scans[0].file_up->z()), 0.03, 1e-9) << "the tilt, not the heading";
  EXPECT_LT((*project.scans[1].file_up - Eigen::Vector3d::UnitZ()).norm(), 1e-12) << "a pose without tilt: upright";
  project.file = dir / "p.scanreg.json";
  project.scans[0].world_from_scan = Eigen::Isometry3d::Identity();  // a registration moved it
  ASSERT_TRUE(io::SaveProject(project, project.file).ok());
  auto loaded = io::LoadProject(project.file);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_TRUE(loaded->scans[0].file_up.has_value());
  EXPECT_LT((*loaded->scans[0].file_up - expect).norm(), 1e-12);
}

TEST(AppendScanFiles, ErrorNamesTheFileAndLeavesTheProjectUnchanged) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  io::Project project;
  NullProgress progress;
  ASSERT_TRUE(AppendScanFiles(project, {ab}, progress, CancelToken()).ok());
  const auto c = WritePtxFile(dir, "c.ptx", {PlaneScan("c", 3.0)});
  const Status bad = AppendScanFiles(project, {c, dir / "missing.ptx"}, progress, CancelToken());
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("missing.ptx"), std::string::npos) << bad.error().message;
  EXPECT_EQ(project.scans.size(), 2u);
}

TEST(CreateProject, SavesTheProjectWithEveryScan) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  const auto ab2 = WritePtxFile(dir, "ab2.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  NullProgress progress;
  CreateProjectOptions options;
  options.scan_files = {ab, ab2};
  auto project = CreateProject(dir / "p.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(project.ok()) << project.error().message;
  auto scans = LoadProjectScans(project->project, progress, CancelToken());  // as the GUI reads them back
  ASSERT_TRUE(scans.ok()) << scans.error().message;
  ASSERT_EQ(scans->size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ((*scans)[i].name, project->project.scans[i].name);
    EXPECT_GT((*scans)[i].CountValid(), 0u);
  }
  auto loaded = io::LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->scans.size(), 4u);
  EXPECT_EQ(loaded->scans[3].name, "ab2_2");

  // The same file twice is noticed: an error naming it (CLI), or left out and listed (GUI).
  options.scan_files = {ab, ab};
  auto twice = CreateProject(dir / "q.scanreg.json", options, progress, CancelToken());
  ASSERT_FALSE(twice.ok());
  EXPECT_NE(twice.error().message.find("already in the project"), std::string::npos) << twice.error().message;
  options.skip_unreadable = true;
  auto listed = CreateProject(dir / "q.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(listed.ok()) << listed.error().message;
  EXPECT_EQ(listed->project.scans.size(), 2u);
  ASSERT_EQ(listed->skipped.size(), 1u);
  EXPECT_NE(listed->skipped[0].find("ab.ptx"), std::string::npos) << listed->skipped[0];
}

// Batch add (issue 14): every readable file is added, every other one is listed with its reason.
TEST(AppendScanFiles, BatchAddAddsEveryReadableFileAndListsEveryError) {
  test::TempDir dir;
  const auto a = WritePtxFile(dir, "a.ptx", {PlaneScan("a", 1.0)});
  const auto b = WritePtxFile(dir, "b.ptx", {PlaneScan("b", 2.0)});
  const std::filesystem::path garbage = dir / "garbage.ptx";
  std::FILE* f = std::fopen(garbage.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("20\n10\nnot a number\n", f);
  std::fclose(f);
  Scan empty("e", 4, 4);
  const auto no_points = WritePtxFile(dir, "empty.ptx", {PlaneScan("c", 3.0), empty});
  io::Project project;
  NullProgress progress;
  std::vector<std::string> skipped;
  const Status added =
      AppendScanFiles(project, {a, dir / "missing.ptx", garbage, no_points, b, a}, progress, CancelToken(), &skipped);
  ASSERT_TRUE(added.ok()) << added.error().message;
  ASSERT_EQ(project.scans.size(), 2u);
  EXPECT_EQ(project.scans[0].name, "a");
  EXPECT_EQ(project.scans[1].name, "b");
  ASSERT_EQ(skipped.size(), 4u);
  EXPECT_NE(skipped[0].find("missing.ptx"), std::string::npos) << skipped[0];
  EXPECT_NE(skipped[1].find("garbage.ptx"), std::string::npos) << skipped[1];
  EXPECT_NE(skipped[2].find("no valid point"), std::string::npos) << skipped[2];
  EXPECT_NE(skipped[3].find("already in the project"), std::string::npos) << skipped[3];
}

// Two poses for one scan in a pose file: refused, naming the scan (it used to take the last one).
TEST(CreateProject, TwoPosesForOneScanAreRefused) {
  test::TempDir dir;
  const auto a = WritePtxFile(dir, "a.ptx", {PlaneScan("a", 0.0)});
  const auto b = WritePtxFile(dir, "b.ptx", {PlaneScan("b", 0.0)});
  const std::vector<io::NamedPose> poses = {{"a", Eigen::Isometry3d::Identity(), ""},
                                            {"a", Eigen::Isometry3d(Eigen::Translation3d(1, 2, 3)), ""}};
  ASSERT_TRUE(io::WritePosesJson(dir / "p.json", poses).ok());
  CreateProjectOptions options;
  options.scan_files = {a, b};
  options.poses = dir / "p.json";
  NullProgress progress;
  auto project = CreateProject(dir / "p.scanreg.json", options, progress, CancelToken());
  ASSERT_FALSE(project.ok());
  EXPECT_NE(project.error().message.find("scan 'a' two poses"), std::string::npos) << project.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir / "p.scanreg.json"));
}

// A pose read from a file is used as it is: the scan is 'imported' (registered, no link evidence).
TEST(CreateProject, EveryPoseFormatExportPosesWritesIsImported) {
  test::TempDir dir;
  Scan a = PlaneScan("a", 0.0), b = PlaneScan("b", 0.0);
  a.world_from_scan = b.world_from_scan = Eigen::Isometry3d::Identity();
  const auto file_a = WritePtxFile(dir, "a.ptx", {a});
  const auto file_b = WritePtxFile(dir, "b.ptx", {b});
  Eigen::Isometry3d pose_b = Eigen::Isometry3d::Identity();
  pose_b.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose_b.translation() = Eigen::Vector3d(500012.5, 4999990.25, 101.0);
  const std::vector<io::NamedPose> poses = {{"a", Eigen::Isometry3d::Identity(), ""}, {"b", pose_b, "registered"}};
  ASSERT_TRUE(io::WritePosesJson(dir / "p.json", poses).ok());
  ASSERT_TRUE(io::WritePosesCsv(dir / "p.csv", poses).ok());
  std::filesystem::create_directories(dir / "txt");
  for (const io::NamedPose& p : poses)
    ASSERT_TRUE(io::WriteMatrixTxt(dir / "txt" / (p.scan + ".txt"), p.world_from_scan).ok());
  for (const std::string pose_file : {"p.json", "p.csv", "txt", "txt/b.txt"}) {
    SCOPED_TRACE(pose_file);
    CreateProjectOptions options;
    options.scan_files = {file_a, file_b};
    options.poses = dir / pose_file;
    NullProgress progress;
    auto project = CreateProject(dir / "p.scanreg.json", options, progress, CancelToken());
    ASSERT_TRUE(project.ok()) << project.error().message;
    auto loaded = io::LoadProject(dir / "p.scanreg.json");
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    const io::ProjectScan& sb = loaded->scans[1];
    EXPECT_EQ(io::ScanPoseState(sb), io::PoseState::kImported);
    EXPECT_LT((sb.world_from_scan.matrix() - pose_b.matrix()).cwiseAbs().maxCoeff(), 1e-9);
    const bool a_listed = pose_file != "txt/b.txt";
    EXPECT_EQ(io::ScanPoseState(loaded->scans[0]), a_listed ? io::PoseState::kImported : io::PoseState::kUnregistered);
  }
  CreateProjectOptions bad;
  bad.scan_files = {file_a};
  bad.poses = dir / "p.xyz";
  NullProgress progress;
  auto refused = CreateProject(dir / "q.scanreg.json", bad, progress, CancelToken());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find(".csv"), std::string::npos) << refused.error().message;
}

TEST(CreateProject, HeaderPosesAreImportedAndASingleScanIsInPlace) {
  test::TempDir dir;
  Scan placed = PlaneScan("placed", 7.0);  // a registered pose in the PTX header (another program's)
  Scan raw = PlaneScan("raw", 0.0);
  raw.world_from_scan = Eigen::Isometry3d::Identity();
  const auto file = WritePtxFile(dir, "two.ptx", {placed, raw});
  NullProgress progress;
  CreateProjectOptions options;
  options.scan_files = {file};
  auto two = CreateProject(dir / "two.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(two.ok()) << two.error().message;
  EXPECT_EQ(io::ScanPoseState(two->project.scans[0]), io::PoseState::kImported);
  EXPECT_EQ(io::ScanPoseState(two->project.scans[1]), io::PoseState::kUnregistered);
  // One scan alone is its own frame: usable by merge and export without registration.
  options.scan_files = {WritePtxFile(dir, "one.ptx", {raw})};
  auto one = CreateProject(dir / "one.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(one.ok()) << one.error().message;
  ASSERT_EQ(one->project.scans.size(), 1u);
  EXPECT_EQ(io::ScanPoseState(one->project.scans[0]), io::PoseState::kRegistered);
}

// Project management (issue 14): rename, remove, set the root, move the files and relink them,
// through save and reopen.
TEST(ProjectManagement, RemoveRenameRelinkRoundTripThroughSaveAndReopen) {
  test::TempDir dir;
  std::filesystem::create_directories(dir / "A");
  const auto a = WritePtxFile(dir, "A/a.ptx", {PlaneScan("a", 1.0)});
  const auto b = WritePtxFile(dir, "A/b.ptx", {PlaneScan("b", 2.0)});
  const auto c = WritePtxFile(dir, "A/c.ptx", {PlaneScan("c", 3.0)});
  NullProgress progress;
  CreateProjectOptions options;
  options.scan_files = {a, b, c};
  auto created = CreateProject(dir / "p.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(created.ok()) << created.error().message;
  io::Project project = created->project;
  project.scans[2].parent_override = "b";
  ASSERT_TRUE(RenameScan("b", "north", project).ok());
  EXPECT_EQ(project.scans[2].parent_override.value_or(""), "north");
  EXPECT_FALSE(RenameScan("a", "north", project).ok()) << "names stay unique";
  EXPECT_FALSE(RenameScan("a", "", project).ok());
  EXPECT_FALSE(RenameScan("a", "bad\nname", project).ok());
  Expected<std::vector<std::string>> orphans = RemoveScan("c", project);
  ASSERT_TRUE(orphans.ok());
  EXPECT_FALSE(RemoveScan("c", project).ok());
  ASSERT_TRUE(SetRoot("north", project).ok());
  ASSERT_TRUE(io::SaveProject(project, dir / "p.scanreg.json").ok());

  // The scan files move to another folder: the project finds them there.
  std::filesystem::rename(dir / "A", dir / "B");
  auto moved = io::LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(moved.ok()) << moved.error().message;
  EXPECT_EQ(MissingScanFiles(*moved), (std::vector<std::string>{"a", "north"}));
  Expected<std::vector<Scan>> not_there = LoadProjectScans(*moved, progress, CancelToken());
  ASSERT_FALSE(not_there.ok());
  EXPECT_EQ(not_there.error().code, ErrorCode::kNotFound);
  EXPECT_NE(not_there.error().message.find("scan 'a'"), std::string::npos) << not_there.error().message;
  EXPECT_NE(not_there.error().message.find("A/a.ptx"), std::string::npos) << not_there.error().message;
  EXPECT_EQ(RelinkFromFolder(*moved, dir / "B"), 2);
  EXPECT_TRUE(MissingScanFiles(*moved).empty());
  ASSERT_TRUE(io::SaveProject(*moved, dir / "p.scanreg.json").ok());

  auto reopened = io::LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(reopened.ok()) << reopened.error().message;
  ASSERT_EQ(reopened->scans.size(), 2u);
  EXPECT_EQ(reopened->scans[0].name, "a");
  EXPECT_EQ(reopened->scans[1].name, "north");
  EXPECT_EQ(reopened->root.value_or(""), "north");
  EXPECT_EQ(reopened->scans[1].path, std::filesystem::absolute(dir / "B" / "b.ptx").lexically_normal());
  auto scans = LoadProjectScans(*reopened, progress, CancelToken());
  ASSERT_TRUE(scans.ok()) << scans.error().message;
  EXPECT_EQ((*scans)[1].name, "north");
  EXPECT_NEAR((*scans)[1].world_from_scan.translation().x(), 2.0, 1e-9);

  // Relinking one scan to a file that holds another scan (another grid) is refused and changes nothing.
  Scan other("x", 5, 5);
  other.Set(0, 0, Eigen::Vector3f(1, 2, 3), 0.5f);
  const auto wrong = WritePtxFile(dir, "other.ptx", {other});
  io::Project before = *reopened;
  Expected<Scan> refused = RelinkScan(*reopened, "north", wrong, &(*scans)[1], progress, CancelToken());
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.error().message.find("not the same scan"), std::string::npos) << refused.error().message;
  EXPECT_EQ(reopened->scans[1].path, before.scans[1].path);
  const auto copy = WritePtxFile(dir, "copy_of_b.ptx", {PlaneScan("b", 2.0)});
  Expected<Scan> relinked = RelinkScan(*reopened, "north", copy, &(*scans)[1], progress, CancelToken());
  ASSERT_TRUE(relinked.ok()) << relinked.error().message;
  EXPECT_EQ(relinked->name, "north");
  EXPECT_EQ(reopened->scans[1].path, std::filesystem::absolute(copy).lexically_normal());
}

}  // namespace
}  // namespace scanreg::pipeline
