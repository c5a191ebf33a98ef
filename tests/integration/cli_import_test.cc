// Imported poses end to end with the real Stanford bunny and its .conf: `new --poses` makes the
// scans 'imported', merge and export use them without `register`, and `register --keep-imported`
// leaves them as they are.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "core/geometry/transform.h"
#include "core/io/project.h"
#include "core/io/scan_file.h"
#include "tests/integration/cli_run.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

using test::Quote;
using test::ReadBytes;
using test::RunCli;
using test::RunResult;

TEST(CliImport, ConfPosesAreImportedMergedExportedAndKept) {
  SCANREG_REQUIRE_REALDATA(data);
  const auto bunny = data / "stanford_bunny";
  test::TempDir dir;
  const auto project_file = dir / "bunny.scanreg.json";
  const std::string p = Quote(project_file);
  RunResult created = RunCli("new " + p + " " + Quote(bunny / "bun000.ply") + " " + Quote(bunny / "bun045.ply") + " " +
                             Quote(bunny / "bun090.ply") + " --poses " + Quote(bunny / "bun.conf"));
  ASSERT_EQ(created.status, 0) << created.output;
  // bun.conf holds all 10 scans: the 7 not in this project are named, not an error.
  EXPECT_NE(created.output.find("7 pose(s) match no scan of the project"), std::string::npos) << created.output;
  RunResult info = RunCli("info " + p);
  ASSERT_EQ(info.status, 0) << info.output;
  std::size_t imported = 0;
  for (std::size_t at = info.output.find(" imported "); at != std::string::npos;
       at = info.output.find(" imported ", at + 1))
    ++imported;
  EXPECT_EQ(imported, 3u) << info.output;
  Expected<io::Project> before = io::LoadProject(project_file);
  ASSERT_TRUE(before.ok());

  // Merge and export without registering.
  RunResult merged = RunCli("merge " + p + " --voxel 0.002 --sigma 0.0005 --out " + Quote(dir / "bunny.ply"));
  ASSERT_EQ(merged.status, 0) << merged.output;
  EXPECT_NE(merged.output.find("merged 3 of 3 scans"), std::string::npos) << merged.output;
  // Without --voxel and --sigma both are sized to this 15 cm object, not the 2 cm / 12 mm of a street.
  RunResult sized = RunCli("merge " + p + " --out " + Quote(dir / "sized.ply"));
  ASSERT_EQ(sized.status, 0) << sized.output;
  const std::size_t at = sized.output.find("sized to the data (--voxel and --sigma choose others): voxel ");
  ASSERT_NE(at, std::string::npos) << sized.output;
  double voxel = 0, sigma = 0;
  ASSERT_EQ(std::sscanf(sized.output.c_str() + sized.output.find(": voxel ", at), ": voxel %lf m, range noise %lf m",
                        &voxel, &sigma), 2) << sized.output;
  EXPECT_GT(voxel, 0.0);
  EXPECT_LE(voxel, 0.002);
  EXPECT_LE(sigma, 0.002);
  // ... and the merge ran with that voxel.
  const std::size_t from = sized.output.find(": voxel ", at) + 8;
  const std::string token = sized.output.substr(from, sized.output.find(" m,", from) - from);
  EXPECT_NE(sized.output.find("(consensus, voxel " + token + " m)"), std::string::npos) << sized.output;
  RunResult clouds = RunCli("export-clouds " + p + " --format las --out " + Quote(dir / "las"));
  ASSERT_EQ(clouds.status, 0) << clouds.output;
  EXPECT_NE(clouds.output.find("exported 3 of 3 scans"), std::string::npos) << clouds.output;
  EXPECT_EQ(ReadBytes(dir / "las" / "bun045.las").substr(0, 4), "LASF");
  RunResult poses = RunCli("export-poses " + p + " --format csv --out " + Quote(dir / "poses.csv"));
  ASSERT_EQ(poses.status, 0) << poses.output;
  EXPECT_NE(ReadBytes(dir / "poses.csv").find(",imported\n"), std::string::npos);

  // A project made from what export-poses wrote has the same poses.
  RunResult again =
      RunCli("new " + Quote(dir / "again.scanreg.json") + " " + Quote(bunny / "bun000.ply") + " " +
             Quote(bunny / "bun045.ply") + " " + Quote(bunny / "bun090.ply") + " --poses " + Quote(dir / "poses.csv"));
  ASSERT_EQ(again.status, 0) << again.output;
  Expected<io::Project> reread = io::LoadProject(dir / "again.scanreg.json");
  ASSERT_TRUE(reread.ok());
  for (int i = 0; i < 3; ++i) {
    // CSV holds angles in degrees: the matrix comes back to rounding (1e-9: a nanometre, a nanoradian).
    EXPECT_LT(
        (reread->scans[i].world_from_scan.matrix() - before->scans[i].world_from_scan.matrix()).cwiseAbs().maxCoeff(),
        1e-9);
  }

  // --keep-imported: the imported poses stay exactly as they were, and it says so.
  RunResult kept = RunCli("register " + p + " --keep-imported --fine em --noise 0.0005 --overlap-distance 0.01");
  EXPECT_EQ(kept.status, 0) << kept.output;
  EXPECT_NE(kept.output.find("kept fixed"), std::string::npos) << kept.output;
  Expected<io::Project> after = io::LoadProject(project_file);
  ASSERT_TRUE(after.ok());
  for (std::size_t i = 0; i < after->scans.size(); ++i) {
    EXPECT_LT(
        (after->scans[i].world_from_scan.matrix() - before->scans[i].world_from_scan.matrix()).cwiseAbs().maxCoeff(),
        1e-12)
        << i;
    EXPECT_EQ(io::ScanPoseState(after->scans[i]), io::PoseState::kImported) << i;
  }
  EXPECT_EQ(after->settings.at("register.keep_imported"), "true");
  EXPECT_EQ(after->settings.at("register.coarse"), "none");  // the pose-based path, chosen for imported poses
  EXPECT_EQ(std::stod(after->settings.at("register.noise_m")), 0.0005);
}

}  // namespace
}  // namespace scanreg

namespace scanreg {
namespace {

// Issue 33: `register` on imported poses, one of them 20° off (about the vertical through the
// object). Whatever the refinement makes of it, a scan the CLI calls registered lies within 1 cm /
// 2° of bun.conf, a scan it cannot verify keeps its imported pose exactly and makes the exit status 3,
// and the consistency it saved is no worse after than at the start.
TEST(CliImport, RegisterOnImportedPosesNeverCallsAWrongScanRegistered) {
  SCANREG_REQUIRE_REALDATA(data);
  for (double degrees : {20.0, 90.0}) {
  const auto bunny = data / "stanford_bunny";
  test::TempDir dir;
  const auto project_file = dir / "bunny.scanreg.json";
  const std::string p = test::Quote(project_file);
  const std::vector<std::string> names = {"bun000", "bun045", "bun315", "bun270"};
  std::string files;
  for (const std::string& n : names) files += " " + test::Quote(bunny / (n + ".ply"));
  test::RunResult created = test::RunCli("new " + p + files + " --poses " + test::Quote(bunny / "bun.conf") +
                                         " --reference-poses " + test::Quote(bunny / "bun.conf"));
  ASSERT_EQ(created.status, 0) << created.output;
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  const Eigen::Vector3d centre(-0.025, 0.1, 0.0);  // about the bunny's middle in bun.conf's frame
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.translate(centre);
  turn.rotate(Eigen::AngleAxisd(degrees * M_PI / 180, Eigen::Vector3d::UnitY()));
  turn.translate(-centre);
  project->scans[3].world_from_scan = turn * project->scans[3].world_from_scan;
  ASSERT_TRUE(io::SaveProject(*project, project_file).ok());
  const std::vector<Eigen::Isometry3d> start = {project->scans[0].world_from_scan, project->scans[1].world_from_scan,
                                                project->scans[2].world_from_scan, project->scans[3].world_from_scan};

  test::RunResult registered = test::RunCli("register " + p);
  Expected<io::Project> after = io::LoadProject(project_file);
  ASSERT_TRUE(after.ok()) << after.error().ToString();
  ASSERT_TRUE(after->consistency.has_value()) << registered.output;
  EXPECT_LE(after->consistency->result_rms_m, after->consistency->start_rms_m) << registered.output;
  EXPECT_NE(registered.output.find("consistency (no ground truth)"), std::string::npos) << registered.output;
  int kept = 0;
  const int root = after->FindScan(after->root.value_or(""));
  ASSERT_GE(root, 0);
  for (std::size_t i = 0; i < after->scans.size(); ++i) {
    const io::ProjectScan& s = after->scans[i];
    ASSERT_TRUE(s.registered) << s.name;  // registered or keeping its imported pose: never dropped
    if (s.imported_pose) {
      ++kept;
      EXPECT_TRUE(s.world_from_scan.isApprox(start[i], 1e-9)) << s.name << " must keep its imported pose";
      EXPECT_FALSE(s.unregistered_reason.empty()) << s.name;
      continue;
    }
    const PoseError e =
        ComparePoses(after->scans[root].world_from_scan.inverse() * s.world_from_scan,
                     after->scans[root].reference_world_from_scan->inverse() * *s.reference_world_from_scan);
    EXPECT_LT(e.position_m, 0.01) << s.name << " called registered " << 1e3 * e.position_m << " mm off\n" << registered.output;
    EXPECT_LT(e.angle_rad, 2.0 * M_PI / 180) << s.name << " called registered " << e.angle_rad * 180 / M_PI << " deg off";
  }
  EXPECT_EQ(registered.status, kept > 0 ? 3 : 0) << registered.output;
  std::printf("bunny, bun270 imported %.0f deg off: exit %d, %d scan(s) kept at their imported pose; consistency %.3f -> %.3f mm\n",
              degrees, registered.status, kept, 1e3 * after->consistency->start_rms_m, 1e3 * after->consistency->result_rms_m);
  }
}

// A time per point is kept where the format can hold it and the user is told where it cannot:
// `convert` of TerraScan's simple.las (a GPS time per point) to PLY writes CloudCompare's
// scalar_GpsTime property with the file's time base, to PCD (no time field) warns, naming the scan.
TEST(CliImport, ConvertKeepsTimesInPlyAndSaysWhereAFormatCannot) {
  SCANREG_REQUIRE_REALDATA(data);
  test::TempDir dir;
  const std::filesystem::path las = data / "las_pdal" / "simple.las";
  RunResult ply = RunCli("convert " + Quote(las) + " " + Quote(dir / "s.ply"));
  ASSERT_EQ(ply.status, 0) << ply.output;
  EXPECT_EQ(ply.output.find("time per point"), std::string::npos) << ply.output;
  const std::string bytes = ReadBytes(dir / "s.ply");
  const std::string header = bytes.substr(0, bytes.find("end_header"));
  EXPECT_NE(header.find("property double scalar_GpsTime"), std::string::npos) << header;
  EXPECT_NE(header.find("obj_info scanreg_time_base GPS week seconds"), std::string::npos) << header;
  RunResult pcd = RunCli("convert " + Quote(las) + " " + Quote(dir / "s.pcd"));
  ASSERT_EQ(pcd.status, 0) << pcd.output;
  EXPECT_NE(pcd.output.find("scan 'simple' has a time per point (GPS week seconds), which pcd does not keep"),
            std::string::npos)
      << pcd.output;
}

}  // namespace
}  // namespace scanreg
