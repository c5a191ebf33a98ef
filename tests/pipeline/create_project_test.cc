// Creating a project from scan files and adding scans to it (the GUI's New project / Add scans):
// unique names, poses from the files, the project unchanged on error.
#include <gtest/gtest.h>

#include "core/io/pose_csv.h"
#include "core/io/ptx.h"
#include "core/pipeline/create_project.h"
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
  auto first = AppendScanFiles(project, {ab}, true, progress, CancelToken());
  ASSERT_TRUE(first.ok()) << first.error().message;
  auto second = AppendScanFiles(project, {a2}, true, progress, CancelToken());
  ASSERT_TRUE(second.ok()) << second.error().message;
  ASSERT_EQ(project.scans.size(), 3u);
  EXPECT_EQ(project.scans[0].name, "ab_1");
  EXPECT_EQ(project.scans[1].name, "ab_2");
  EXPECT_EQ(project.scans[2].name, "ab_1_2");
  EXPECT_EQ(project.scans[1].index_in_file, 1);
  ASSERT_EQ(second->size(), 1u);
  EXPECT_EQ((*second)[0].name, "ab_1_2");
  EXPECT_EQ((*second)[0].CountValid(), PlaneScan("a", 0).CountValid());
  EXPECT_NEAR(project.scans[2].world_from_scan.translation().x(), 3.0, 1e-9);
  EXPECT_NEAR(project.scans[1].world_from_scan.translation().x(), 2.0, 1e-9);
}

TEST(AppendScanFiles, WithoutKeepingScansReturnsNoneButAppends) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  io::Project project;
  NullProgress progress;
  auto scans = AppendScanFiles(project, {ab}, false, progress, CancelToken());
  ASSERT_TRUE(scans.ok());
  EXPECT_TRUE(scans->empty());
  EXPECT_EQ(project.scans.size(), 2u);
}

TEST(AppendScanFiles, ErrorNamesTheFileAndLeavesTheProjectUnchanged) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  io::Project project;
  NullProgress progress;
  ASSERT_TRUE(AppendScanFiles(project, {ab}, false, progress, CancelToken()).ok());
  auto bad = AppendScanFiles(project, {ab, dir / "missing.ptx"}, true, progress, CancelToken());
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("missing.ptx"), std::string::npos) << bad.error().message;
  EXPECT_EQ(project.scans.size(), 2u);
}

TEST(CreateProject, SavesTheProjectWithEveryScan) {
  test::TempDir dir;
  const auto ab = WritePtxFile(dir, "ab.ptx", {PlaneScan("a", 1.0), PlaneScan("b", 2.0)});
  NullProgress progress;
  CreateProjectOptions options;
  options.scan_files = {ab, ab};
  options.keep_scans = true;  // as the GUI creates a project: the scans come back, named as in it
  auto project = CreateProject(dir / "p.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(project.ok()) << project.error().message;
  ASSERT_EQ(project->scans.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(project->scans[i].name, project->project.scans[i].name);
    EXPECT_GT(project->scans[i].CountValid(), 0u);
  }
  auto loaded = io::LoadProject(dir / "p.scanreg.json");
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  ASSERT_EQ(loaded->scans.size(), 4u);
  EXPECT_EQ(loaded->scans[3].name, "ab_2_2");
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
  EXPECT_TRUE(two->scans.empty());  // without keep_scans the points are dropped once checked
  // One scan alone is its own frame: usable by merge and export without registration.
  options.scan_files = {WritePtxFile(dir, "one.ptx", {raw})};
  auto one = CreateProject(dir / "one.scanreg.json", options, progress, CancelToken());
  ASSERT_TRUE(one.ok()) << one.error().message;
  ASSERT_EQ(one->project.scans.size(), 1u);
  EXPECT_EQ(io::ScanPoseState(one->project.scans[0]), io::PoseState::kRegistered);
}

}  // namespace
}  // namespace scanreg::pipeline
