// Exporting registered scans with the true poses as the registration: poses kept in the header
// read back equal, poses applied put every point where the true pose puts it.
#include "core/pipeline/export_clouds.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/common/log.h"
#include "core/geometry/transform.h"
#include "core/io/las_reader.h"
#include "core/io/scan_file.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

// Two stations registered at their true poses and a far station left unregistered.
io::Project TrueProject(const std::filesystem::path& dir) {
  SimulatedProjectOptions o;
  o.stations = 2;
  o.scanner.cols = 300;
  o.scanner.rows = 80;
  o.seed = o.scanner.seed = o.scene.seed = 4;
  o.add_far_station = true;
  NullProgress progress;
  CancelToken cancel;
  Expected<io::Project> project = WriteSimulatedProject(o, dir, progress, cancel);
  EXPECT_TRUE(project.ok()) << project.error().ToString();
  if (!project.ok()) return {};
  for (int i = 0; i < 2; ++i) {
    project->scans[i].world_from_scan = *project->scans[i].reference_world_from_scan;
    project->scans[i].registered = true;
  }
  project->scans[2].unregistered_reason = "no overlap";
  return *project;
}

class ExportCloudsTest : public ::testing::TestWithParam<std::string> {};

TEST_P(ExportCloudsTest, KeptPosesReadBackEqualAndAppliedPosesPutPointsAtTheTruth) {
  test::TempDir dir;
  const io::Project project = TrueProject(dir / "p");
  ASSERT_EQ(project.scans.size(), 3u);
  NullProgress progress;
  CancelToken cancel;
  auto originals = LoadProjectScans(project, progress, cancel);
  ASSERT_TRUE(originals.ok()) << originals.error().ToString();
  for (bool apply : {false, true}) {
    ExportCloudsOptions options;
    options.dir = dir / (apply ? "applied" : "kept");
    options.format = GetParam();
    options.apply_poses = apply;
    auto exported = ExportClouds(project, options, progress, cancel);
    ASSERT_TRUE(exported.ok()) << exported.error().ToString();
    ASSERT_EQ(exported->size(), 3u);
    EXPECT_TRUE((*exported)[2].file.empty());
    EXPECT_NE((*exported)[2].skipped.find("no overlap"), std::string::npos) << (*exported)[2].skipped;
    EXPECT_FALSE(std::filesystem::exists(options.dir / ("s03." + GetParam())));
    for (int i = 0; i < 2; ++i) {
      const Scan& original = (*originals)[i];
      const Eigen::Isometry3d truth = *project.scans[i].reference_world_from_scan;
      auto read = io::ReadScanFile((*exported)[i].file, progress, cancel);
      ASSERT_TRUE(read.ok()) << read.error().ToString();
      ASSERT_EQ(read->size(), 1u);
      const Scan& back = (*read)[0];
      ASSERT_EQ(back.rows, original.rows);
      ASSERT_EQ(back.cols, original.cols);
      EXPECT_EQ(back.CountValid(), original.CountValid());
      EXPECT_EQ((*exported)[i].points, original.CountValid());
      // PLY always holds world coordinates (doubles) with the pose: scanreg reads back the same scan.
      const bool applied = apply && !WorldFormat(GetParam());
      const Eigen::Isometry3d expected_header = applied ? Eigen::Isometry3d::Identity() : truth;
      // (ComparePoses' angle bottoms out near 2e-8 rad, the acos of a trace near 3; compare entries.)
      const double header = (back.world_from_scan.matrix() - expected_header.matrix()).cwiseAbs().maxCoeff();
      EXPECT_LT(header, 1e-9) << original.name << ": header pose";
      double worst = 0;
      for (std::size_t k = 0; k < original.size(); ++k) {
        if (!original.valid[k]) continue;
        ASSERT_TRUE(back.valid[k]) << original.name << " cell " << k;
        const Eigen::Vector3d want =
            applied ? truth * original.points[k].cast<double>() : original.points[k].cast<double>();
        worst = std::max(worst, (back.points[k].cast<double>() - want).norm());
      }
      EXPECT_LT(worst, 1e-4) << original.name << ": farthest point from where the true pose puts it (m)";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, ExportCloudsTest, ::testing::Values("ptx", "ply", "e57"));

// LAS names two time bases only (GPS week seconds, adjusted standard GPS time): a scan whose times
// count from something else (a PLY's time without a base) is exported with its times as they are
// and a warning that names the file, the scan and what keeps the base; a LAS base gives none.
TEST(ExportClouds, LasSaysWhenItCannotNameTheTimeBase) {
  test::TempDir dir;
  io::Project project = TrueProject(dir / "p");
  NullProgress progress;
  CancelToken cancel;
  auto scans = LoadProjectScans(project, progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  Scan timed = (*scans)[0];
  timed.AddTime();
  for (std::size_t i = 0; i < timed.size(); ++i) timed.time[i] = 0.001 * double(i);
  for (const std::string base : {std::string(), std::string(io::kGpsWeekSeconds)}) {
    SCOPED_TRACE(base.empty() ? "no base" : base);
    timed.time_base = base;
    const std::filesystem::path file = dir / (base.empty() ? "timed.ply" : "week.ply");
    ASSERT_TRUE(io::WriteScanFile(file, {timed}, progress, cancel).ok());
    project.scans[0].path = file;
    std::vector<std::string> warnings;
    SetLogHandler([&](LogLevel level, const std::string& m) {
      if (level == LogLevel::kWarning) warnings.push_back(m);
    });
    ExportCloudsOptions options;
    options.dir = dir / (base.empty() ? "las" : "las_week");
    options.format = "las";
    auto exported = ExportClouds(project, options, progress, cancel);
    SetLogHandler({});
    ASSERT_TRUE(exported.ok()) << exported.error().ToString();
    int about_time = 0;
    for (const std::string& w : warnings)
      if (w.find("LAS cannot name") != std::string::npos) {
        ++about_time;
        EXPECT_NE(w.find((*exported)[0].file.filename().string()), std::string::npos) << w;
        EXPECT_NE(w.find("an unknown base"), std::string::npos) << w;
      }
    EXPECT_EQ(about_time, base.empty() ? 1 : 0);
  }
}

TEST(ExportClouds, RefusesToOverwriteInputsAndNeedsARegisteredScan) {
  test::TempDir dir;
  io::Project project = TrueProject(dir / "p");
  ASSERT_EQ(project.scans.size(), 3u);
  NullProgress progress;
  CancelToken cancel;
  ExportCloudsOptions options;
  options.dir = dir / "p";  // the simulated PTX files are here
  auto onto_inputs = ExportClouds(project, options, progress, cancel);
  ASSERT_FALSE(onto_inputs.ok());
  EXPECT_NE(onto_inputs.error().message.find("overwrite"), std::string::npos) << onto_inputs.error().message;
  for (io::ProjectScan& s : project.scans) s.registered = false;
  options.dir = dir / "out";
  auto none = ExportClouds(project, options, progress, cancel);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().message.find("register"), std::string::npos) << none.error().message;
  options.format = "xyz";
  EXPECT_EQ(ExportClouds(project, options, progress, cancel).error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace scanreg::pipeline

namespace scanreg::pipeline {
namespace {

// A set of clouds is complete or not there (issue 16, item 5): the second scan's file is damaged,
// so the export stops there and removes the first cloud it wrote; a cloud that existed before stays.
TEST(ExportClouds, AnExportThatStopsHalfwayRemovesTheCloudsItCreated) {
  test::TempDir dir;
  io::Project project = TrueProject(dir / "p");
  ASSERT_EQ(project.scans.size(), 3u);
  project.scans[2].registered = true;  // the far station, exported last
  std::filesystem::resize_file(project.scans[2].path, 200);  // truncated: unreadable
  ExportCloudsOptions options;
  options.format = "ply";
  options.dir = dir / "out";
  std::filesystem::create_directories(options.dir);
  const std::filesystem::path earlier = options.dir / (project.scans[1].name + ".ply");
  std::ofstream(earlier) << "an earlier export";
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<ExportedScan>> r = ExportClouds(project, options, progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("removed the 1 new file(s)"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(project.scans[2].path.filename().string()), std::string::npos)
      << "names the damaged scan file: " << r.error().message;
  EXPECT_FALSE(std::filesystem::exists(options.dir / (project.scans[0].name + ".ply")));
  EXPECT_TRUE(std::filesystem::exists(earlier)) << "a file that existed before is not deleted";
}

}  // namespace
}  // namespace scanreg::pipeline
