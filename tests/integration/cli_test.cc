// Runs scanreg-cli end to end: simulate, new, info, export-poses, convert (also through E57), and bad input.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/geometry/transform.h"
#include "core/io/pose_file.h"
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

TEST(CliTest, SimulateIsDeterministicAndWritesReferencePoses) {
  test::TempDir dir;
  const std::string common = "simulate --stations 3 --size 400x100 --noise 0.012 --seed 7 --out ";
  RunResult a = RunCli(common + Quote(dir / "a"));
  ASSERT_EQ(a.status, 0) << a.output;
  RunResult b = RunCli(common + Quote(dir / "b"));
  ASSERT_EQ(b.status, 0) << b.output;
  for (const char* name : {"s01.ptx", "s02.ptx", "s03.ptx"}) {
    const std::string fa = ReadBytes(dir / "a" / name), fb = ReadBytes(dir / "b" / name);
    ASSERT_GT(fa.size(), 1000u) << name;
    EXPECT_TRUE(fa == fb) << name << " differs between two runs with the same seed";
  }
  RunResult c = RunCli("simulate --stations 3 --size 400x100 --seed 8 --out " + Quote(dir / "c"));
  ASSERT_EQ(c.status, 0) << c.output;
  EXPECT_FALSE(ReadBytes(dir / "a" / "s01.ptx") == ReadBytes(dir / "c" / "s01.ptx")) << "another seed, another scan";

  Expected<io::Project> project = io::LoadProject(dir / "a" / "project.scanreg.json");
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  ASSERT_EQ(project->scans.size(), 3u);
  for (const io::ProjectScan& s : project->scans) {
    ASSERT_TRUE(s.reference_world_from_scan.has_value()) << s.name;
    EXPECT_TRUE(s.world_from_scan.isApprox(Eigen::Isometry3d::Identity())) << "scans arrive unregistered";
  }
  // Stations about 5 m apart (default spacing, with jitter).
  const double d = (project->scans[1].reference_world_from_scan->translation() -
                    project->scans[0].reference_world_from_scan->translation())
                       .norm();
  EXPECT_GT(d, 3.0);
  EXPECT_LT(d, 7.0);
}

// simulate --format e57: the same scans as PTX (both keep the floats exactly), on less disk.
TEST(CliTest, SimulateWritesE57ScansWithThePtxPoints) {
  test::TempDir dir;
  const std::string common = "simulate --stations 2 --size 400x100 --seed 3 --out ";
  ASSERT_EQ(RunCli(common + Quote(dir / "ptx")).status, 0);
  RunResult e57 = RunCli(common + Quote(dir / "e57") + " --format e57");
  ASSERT_EQ(e57.status, 0) << e57.output;
  Expected<io::Project> project = io::LoadProject(dir / "e57" / "project.scanreg.json");
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  ASSERT_EQ(project->scans.size(), 2u);
  for (const io::ProjectScan& ps : project->scans) {
    EXPECT_EQ(ps.path.extension(), ".e57") << ps.name;
    const std::filesystem::path ptx = dir / "ptx" / (ps.name + ".ptx");
    EXPECT_LT(std::filesystem::file_size(ps.path), std::filesystem::file_size(ptx)) << ps.name;
    NullProgress progress;
    CancelToken cancel;
    auto a = io::ReadScanFile(ptx, progress, cancel), b = io::ReadScanFile(ps.path, progress, cancel);
    ASSERT_TRUE(a.ok() && b.ok()) << ps.name;
    const Scan &sa = a->front(), &sb = b->front();
    ASSERT_EQ(sa.rows, sb.rows);
    ASSERT_EQ(sa.cols, sb.cols);
    ASSERT_GT(sb.CountValid(), sb.size() / 4) << ps.name;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < sa.size(); ++i) {
      if (sa.valid[i] != sb.valid[i]) ++differ;
      else if (sa.valid[i] && (sa.points[i] - sb.points[i]).norm() > 1e-4f) ++differ;
    }
    EXPECT_EQ(differ, 0u) << ps.name;
    EXPECT_TRUE(sb.world_from_scan.isApprox(Eigen::Isometry3d::Identity())) << "scans arrive unregistered";
  }
  RunResult bad = RunCli(common + Quote(dir / "bad") + " --format las");
  EXPECT_NE(bad.status, 0);
  EXPECT_NE(bad.output.find("--format must be 'ptx' or 'e57'"), std::string::npos) << bad.output;
}

TEST(CliTest, NewInfoExportAndConvertWorkTogether) {
  test::TempDir dir;
  ASSERT_EQ(RunCli("simulate --stations 2 --size 300x80 --out " + Quote(dir / "sim")).status, 0);
  // The simulated scans are not registered: export-poses writes no pose for them (another program
  // would place an identity at the origin) and says so.
  RunResult exported = RunCli("export-poses " + Quote(dir / "sim" / "project.scanreg.json") + " --format json --out " +
                              Quote(dir / "identity.json"));
  ASSERT_EQ(exported.status, 0) << exported.output;
  EXPECT_NE(exported.output.find("2 of 2 scans are not registered (s01, s02)"), std::string::npos) << exported.output;
  Expected<std::vector<io::NamedPose>> poses = io::ReadPosesJson(dir / "identity.json");
  ASSERT_TRUE(poses.ok());
  ASSERT_EQ(poses->size(), 0u);
  // Poses from a file become the scans' imported poses in a new project.
  poses->push_back({"s01", Eigen::Isometry3d::Identity()});
  poses->push_back({"s02", Eigen::Isometry3d::Identity()});
  (*poses)[1].world_from_scan.translation() << 1.0, 2.0, 3.0;
  ASSERT_TRUE(io::WritePosesJson(dir / "moved.json", *poses).ok());

  const std::string before = ReadBytes(dir / "sim" / "s01.ptx");
  RunResult created = RunCli("new " + Quote(dir / "mine.scanreg.json") + " " + Quote(dir / "sim" / "s01.ptx") + " " +
                             Quote(dir / "sim" / "s02.ptx") + " --poses " + Quote(dir / "moved.json"));
  ASSERT_EQ(created.status, 0) << created.output;
  EXPECT_EQ(ReadBytes(dir / "sim" / "s01.ptx"), before) << "input files are never modified";
  Expected<io::Project> mine = io::LoadProject(dir / "mine.scanreg.json");
  ASSERT_TRUE(mine.ok());
  EXPECT_NEAR(mine->scans[1].world_from_scan.translation().y(), 2.0, 1e-12);

  RunResult info = RunCli("info " + Quote(dir / "mine.scanreg.json"));
  ASSERT_EQ(info.status, 0) << info.output;
  EXPECT_NE(info.output.find("300x80"), std::string::npos) << info.output;
  EXPECT_NE(info.output.find("s02"), std::string::npos);

  RunResult txt =
      RunCli("export-poses " + Quote(dir / "mine.scanreg.json") + " --format txt --out " + Quote(dir / "txt"));
  ASSERT_EQ(txt.status, 0) << txt.output;
  Expected<Eigen::Isometry3d> m = io::ReadMatrixTxt(dir / "txt" / "s02.txt");
  ASSERT_TRUE(m.ok());
  EXPECT_NEAR(m->translation().z(), 3.0, 1e-9);

  RunResult conv = RunCli("convert " + Quote(dir / "sim" / "s01.ptx") + " " + Quote(dir / "s01.ply"));
  ASSERT_EQ(conv.status, 0) << conv.output;
  CancelToken cancel;
  NullProgress progress;
  auto ptx = io::ReadScanFile(dir / "sim" / "s01.ptx", progress, cancel);
  auto ply = io::ReadScanFile(dir / "s01.ply", progress, cancel);
  ASSERT_TRUE(ptx.ok() && ply.ok());
  ASSERT_EQ((*ply)[0].rows, (*ptx)[0].rows);
  ASSERT_EQ((*ply)[0].cols, (*ptx)[0].cols);
  EXPECT_EQ((*ply)[0].CountValid(), (*ptx)[0].CountValid());
  EXPECT_TRUE((*ply)[0].valid == (*ptx)[0].valid);
}

TEST(CliTest, ConvertThroughE57KeepsScansGridAndPosesAndFeedsANewProject) {
  test::TempDir dir;
  ASSERT_EQ(RunCli("simulate --stations 2 --size 300x80 --out " + Quote(dir / "sim")).status, 0);
  CancelToken cancel;
  NullProgress progress;
  auto a = io::ReadScanFile(dir / "sim" / "s01.ptx", progress, cancel);
  auto b = io::ReadScanFile(dir / "sim" / "s02.ptx", progress, cancel);
  ASSERT_TRUE(a.ok() && b.ok());
  std::vector<Scan> scans = {(*a)[0], (*b)[0]};
  scans[1].world_from_scan.linear() =
      Eigen::AngleAxisd(0.8, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()).toRotationMatrix();
  scans[1].world_from_scan.translation() << 523456.125, 4.25, -1.5;
  ASSERT_TRUE(io::WriteScanFile(dir / "both.ptx", scans, progress, cancel).ok());

  RunResult to_e57 = RunCli("convert " + Quote(dir / "both.ptx") + " " + Quote(dir / "both.e57"));
  ASSERT_EQ(to_e57.status, 0) << to_e57.output;
  EXPECT_NE(to_e57.output.find("converted 2 scan(s)"), std::string::npos) << to_e57.output;
  RunResult to_ptx = RunCli("convert " + Quote(dir / "both.e57") + " " + Quote(dir / "back.ptx"));
  ASSERT_EQ(to_ptx.status, 0) << to_ptx.output;
  auto back = io::ReadScanFile(dir / "back.ptx", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const Scan& want = scans[k];
    const Scan& got = (*back)[k];
    ASSERT_EQ(got.rows, want.rows);
    ASSERT_EQ(got.cols, want.cols);
    ASSERT_TRUE(got.valid == want.valid);
    float max_err = 0.0f;
    for (std::size_t i = 0; i < want.size(); ++i)
      if (want.valid[i]) max_err = std::max(max_err, (got.points[i] - want.points[i]).norm());
    EXPECT_EQ(max_err, 0.0f) << "E57 stores the scan's floats";
    EXPECT_LE((got.world_from_scan.matrix() - want.world_from_scan.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  }

  // --scan: only the chosen scan of the E57 file.
  RunResult one = RunCli("convert " + Quote(dir / "both.e57") + " " + Quote(dir / "one.ptx") + " --scan both_2");
  ASSERT_EQ(one.status, 0) << one.output;
  auto second = io::ReadScanFile(dir / "one.ptx", progress, cancel);
  ASSERT_TRUE(second.ok()) << second.error().ToString();
  ASSERT_EQ(second->size(), 1u);
  EXPECT_TRUE((*second)[0].valid == scans[1].valid);
  EXPECT_LE(((*second)[0].world_from_scan.matrix() - scans[1].world_from_scan.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  RunResult missing = RunCli("convert " + Quote(dir / "both.e57") + " " + Quote(dir / "x.ptx") + " --scan s09");
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("no scan named 's09'; the file holds 'both_1', 'both_2'"), std::string::npos)
      << missing.output;

  RunResult created = RunCli("new " + Quote(dir / "e57.scanreg.json") + " " + Quote(dir / "both.e57"));
  ASSERT_EQ(created.status, 0) << created.output;
  Expected<io::Project> project = io::LoadProject(dir / "e57.scanreg.json");
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  ASSERT_EQ(project->scans.size(), 2u);
  EXPECT_EQ(project->scans[1].index_in_file, 1);
  EXPECT_LE((project->scans[1].world_from_scan.matrix() - scans[1].world_from_scan.matrix()).cwiseAbs().maxCoeff(),
            1e-9);
  RunResult info = RunCli("info " + Quote(dir / "e57.scanreg.json"));
  ASSERT_EQ(info.status, 0) << info.output;
  EXPECT_NE(info.output.find("300x80"), std::string::npos) << info.output;
}

TEST(CliTest, BadInputGivesOneClearLineAndNonZeroExit) {
  test::TempDir dir;
  struct Case {
    std::string args;
    std::string expected;  // a fragment of the message
  };
  std::ofstream(dir / "broken.ptx")
      << "10\n10\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 2 3 0.5\n";
  const std::vector<Case> cases = {
      {"frobnicate", "unknown command"},
      {"simulate --stations 0 --out " + Quote(dir / "x"), "--stations"},
      {"simulate --size 12by4 --out " + Quote(dir / "x"), "--size"},
      {"simulate --noise -1 --out " + Quote(dir / "x"), "--noise"},
      {"simulate --bogus", "unknown option '--bogus'"},
      {"info " + Quote(dir / "absent.scanreg.json"), "absent.scanreg.json"},
      {"new " + Quote(dir / "p.scanreg.json") + " " + Quote(dir / "broken.ptx"), "broken.ptx"},
      {"convert " + Quote(dir / "broken.ptx") + " " + Quote(dir / "out.ply"), "line"},
      {"export-poses " + Quote(dir / "absent.scanreg.json") + " --format yaml --out x", "--format"},
  };
  for (const Case& c : cases) {
    RunResult r = RunCli(c.args);
    EXPECT_NE(r.status, 0) << c.args;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find("scanreg-cli"), std::string::npos) << c.args;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out.ply")) << "a failed conversion writes nothing";
}

TEST(CliTest, RegisterUpdatesTheProjectAndReportsTheFarStation) {
  test::TempDir dir;
  RunResult sim =
      RunCli("simulate --stations 3 --spacing 4 --size 1200x300 --far-station --seed 2 --out " + Quote(dir / "p"));
  ASSERT_EQ(sim.status, 0) << sim.output;
  const auto project_file = dir / "p" / "project.scanreg.json";
  RunResult reg = RunCli("register " + Quote(project_file) + " --json");
  // The far station cannot be registered: exit status 3, and the reason is in the output.
  EXPECT_EQ(reg.status, 3) << reg.output;
  EXPECT_NE(reg.output.find("could not be registered"), std::string::npos) << reg.output;
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok());
  ASSERT_EQ(project->scans.size(), 4u);
  for (int i = 0; i < 3; ++i) {
    const io::ProjectScan& s = project->scans[i];
    ASSERT_TRUE(s.registered) << s.name;
    // Relative to the root (s-root is where registration put its datum), compare with the truth.
    const io::ProjectScan& root = project->scans[project->FindScan(project->root.value_or("s01"))];
    const Eigen::Isometry3d est = root.world_from_scan.inverse() * s.world_from_scan;
    const Eigen::Isometry3d ref = root.reference_world_from_scan->inverse() * *s.reference_world_from_scan;
    EXPECT_LT(ComparePoses(est, ref).position_m, 0.03) << s.name;
  }
  EXPECT_FALSE(project->scans[3].registered);
  int ok_links = 0;
  for (const io::LinkRecord& l : project->links) ok_links += l.status != io::LinkStatus::kFailed && !l.loop_check;
  EXPECT_EQ(ok_links, 2);
  // A nonsense option is refused before anything runs.
  RunResult bad = RunCli("register " + Quote(project_file) + " --coarse magic");
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find("--coarse"), std::string::npos);
}

TEST(CliTest, DemoRegistersMergesAndReportsASimulatedProject) {
  test::TempDir dir;
  RunResult demo = RunCli("demo --stations 3 --size 1500x375 --out " + Quote(dir / "demo"));
  ASSERT_EQ(demo.status, 0) << demo.output;  // 0: every scan registered (3 would mean one was not)
  Expected<io::Project> project = io::LoadProject(dir / "demo" / "project.scanreg.json");
  ASSERT_TRUE(project.ok()) << project.error().ToString();
  for (const io::ProjectScan& s : project->scans) {
    ASSERT_TRUE(s.registered) << s.name;
    // Against the simulator's truth, relative to the root (the demo's poses start unknown).
    const io::ProjectScan& root = project->scans[project->FindScan(*project->root)];
    const Eigen::Isometry3d got = root.world_from_scan.inverse() * s.world_from_scan;
    const Eigen::Isometry3d truth = root.reference_world_from_scan->inverse() * *s.reference_world_from_scan;
    EXPECT_LT((got.translation() - truth.translation()).norm(), 0.01) << s.name;
  }
  std::ifstream mesh(dir / "demo" / "merged.ply", std::ios::binary);
  std::string line;
  long faces = -1;
  while (std::getline(mesh, line) && line != "end_header")
    if (line.rfind("element face ", 0) == 0) faces = std::stol(line.substr(13));
  EXPECT_GT(faces, 1000);
  const std::string html = test::ReadBytes(dir / "demo" / "report" / "index.html");
  EXPECT_NE(html.find("id=\"links-table\""), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "demo" / "report" / "network.png"));
}

TEST(CliTest, MergeWritesAMeshOfTheRegisteredScansOnly) {
  test::TempDir dir;
  ASSERT_EQ(RunCli("simulate --stations 2 --size 600x150 --out " + Quote(dir / "p")).status, 0);
  const auto project_file = dir / "p" / "project.scanreg.json";
  // Nothing registered yet: a clear error, no file.
  RunResult none = RunCli("merge " + Quote(project_file) + " --method tsdf --out " + Quote(dir / "m.ply"));
  EXPECT_NE(none.status, 0);
  EXPECT_NE(none.output.find("register"), std::string::npos) << none.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "m.ply"));
  // Register by hand at the true poses, then merge.
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok());
  for (io::ProjectScan& s : project->scans) {
    s.world_from_scan = *s.reference_world_from_scan;
    s.registered = true;
  }
  ASSERT_TRUE(io::SaveProject(*project, project_file).ok());
  RunResult merged = RunCli("merge " + Quote(project_file) + " --method tsdf --voxel 0.2 --max-range 15 --out " +
                            Quote(dir / "m.ply") + " --points " + Quote(dir / "p.ply"));
  ASSERT_EQ(merged.status, 0) << merged.output;
  std::ifstream in(dir / "m.ply", std::ios::binary);
  std::string line;
  long faces = -1;
  while (std::getline(in, line) && line != "end_header")
    if (line.rfind("element face ", 0) == 0) faces = std::stol(line.substr(13));
  EXPECT_GT(faces, 1000) << "a street within 15 m at 20 cm voxels has thousands of triangles";
  EXPECT_NE(merged.output.find(std::to_string(faces) + " triangles"), std::string::npos) << merged.output;
  // The merged point cloud (--points): the mesh's vertices.
  std::ifstream points(dir / "p.ply", std::ios::binary);
  long vertices = -1;
  while (std::getline(points, line) && line != "end_header")
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stol(line.substr(15));
  EXPECT_NE(merged.output.find(std::to_string(vertices) + " vertices"), std::string::npos) << merged.output;
  EXPECT_NE(merged.output.find("merged point cloud: " + std::to_string(vertices) + " points"), std::string::npos);
  // The mesh went through temporary files beside the output (merge::MeshSpill), none left behind.
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().rfind(".scanreg-mesh", 0), std::string::npos) << entry.path();
  // Ctrl-C during a long merge (maximum likelihood at 1 cm): it stops, exits with 130, and leaves
  // neither the output nor its temporary files (KILL after a minute if it did not stop).
  const RunResult interrupted =
      test::RunCommand("timeout --preserve-status -s INT -k 60 2 " + std::string(SCANREG_CLI) + " merge " +
                       Quote(project_file) + " --method ml --voxel 0.01 --out " + Quote(dir / "long.ply"));
  EXPECT_EQ(interrupted.status, 130) << interrupted.output;
  EXPECT_NE(interrupted.output.find("cancelled"), std::string::npos) << interrupted.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "long.ply"));
  for (const auto& entry : std::filesystem::directory_iterator(dir.path()))
    EXPECT_EQ(entry.path().filename().string().rfind(".scanreg-mesh", 0), std::string::npos) << entry.path();
  // Nonsense options are refused.
  EXPECT_EQ(RunCli("merge " + Quote(project_file) + " --voxel 0 --out " + Quote(dir / "x.ply")).status, 2);
  // Options that cannot mean anything are refused at once (the fuzz run: 277 s for --sigma 1e9, a
  // crash for a 100000 x 50000 panorama).
  EXPECT_EQ(RunCli("merge " + Quote(project_file) + " --sigma 1e9 --out " + Quote(dir / "x.ply")).status, 2);
  EXPECT_EQ(RunCli("simulate --stations 2 --size 100000x50000 --out " + Quote(dir / "huge")).status, 2);
  EXPECT_EQ(RunCli("merge " + Quote(project_file) + " --method magic --out " + Quote(dir / "x.ply")).status, 2);
  EXPECT_EQ(
      RunCli("merge " + Quote(project_file) + " --points " + Quote(dir / "x.xyz") + " --out " + Quote(dir / "x.ply"))
          .status,
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

TEST(CliTest, HelpListsEverySubcommand) {
  RunResult r = RunCli("--help");
  EXPECT_EQ(r.status, 0);
  for (const char* c : {"demo", "simulate", "register", "merge", "new", "info", "export-poses", "convert"})
    EXPECT_NE(r.output.find(c), std::string::npos) << c;
}

// Two scans that only the walls seen from above place (no loop can check the pose): the scan is
// "not verified" in the listing, the JSON and the exit status (3), told apart from a scan that could
// not be placed; once the user accepts its link, the next registration registers it at the truth.
TEST(CliTest, AScanPlacedButNotVerifiedSaysSoUntilItsLinkIsAccepted) {
  test::TempDir dir;
  ASSERT_EQ(RunCli("simulate --stations 2 --spacing 6 --size 1000x250 --out " + Quote(dir / "p")).status, 0);
  const auto file = dir / "p" / "project.scanreg.json";
  RunResult reg = RunCli("register " + Quote(file));
  EXPECT_EQ(reg.status, 3) << reg.output;
  EXPECT_NE(reg.output.find("NOT VERIFIED"), std::string::npos) << reg.output;
  EXPECT_NE(reg.output.find("1 were placed but not verified"), std::string::npos) << reg.output;
  EXPECT_EQ(reg.output.find("could not be registered"), std::string::npos) << reg.output;
  Expected<io::Project> project = io::LoadProject(file);
  ASSERT_TRUE(project.ok());
  int waiting = -1;
  for (std::size_t i = 0; i < project->scans.size(); ++i)
    if (io::ScanPoseState(project->scans[i]) == io::PoseState::kNotVerified) waiting = static_cast<int>(i);
  ASSERT_GE(waiting, 0);
  const std::string child = project->scans[waiting].name, parent = project->scans[1 - waiting].name;
  RunResult json = RunCli("register " + Quote(file) + " --json");
  EXPECT_EQ(json.status, 3);
  EXPECT_NE(json.output.find("\"status\": \"not verified\""), std::string::npos) << json.output;

  ASSERT_EQ(RunCli("link " + Quote(file) + " " + parent + " " + child + " --accept").status, 0);
  RunResult again = RunCli("register " + Quote(file));
  ASSERT_EQ(again.status, 0) << again.output;
  project = io::LoadProject(file);
  ASSERT_TRUE(project.ok());
  const io::ProjectScan& a = project->scans[0];
  const io::ProjectScan& b = project->scans[1];
  ASSERT_TRUE(a.registered && b.registered);
  EXPECT_EQ(io::ScanPoseState(project->scans[waiting]), io::PoseState::kRegistered);
  const PoseError e = ComparePoses(a.world_from_scan.inverse() * b.world_from_scan,
                                   a.reference_world_from_scan->inverse() * *b.reference_world_from_scan);
  EXPECT_LT(e.position_m, 0.02);
  EXPECT_LT(e.angle_rad, 0.1 * M_PI / 180);
}

// The user's decision on a link from the command line (the GUI's right-click on the scan network):
// saved in the project, and kept by the next registration; nonsense names a clear error.
TEST(CliTest, LinkRecordsTheUsersDecisionAndRegisterKeepsIt) {
  test::TempDir dir;
  ASSERT_EQ(RunCli("simulate --stations 3 --spacing 4 --size 600x150 --seed 2 --out " + Quote(dir / "p")).status, 0);
  const auto file = dir / "p" / "project.scanreg.json";
  RunResult reg = RunCli("register " + Quote(file));
  ASSERT_EQ(reg.status, 0) << reg.output;
  Expected<io::Project> project = io::LoadProject(file);
  ASSERT_TRUE(project.ok());
  const io::LinkRecord* tree = nullptr;
  for (const io::LinkRecord& l : project->links)
    if (!tree && !l.loop_check && l.status != io::LinkStatus::kFailed) tree = &l;
  ASSERT_NE(tree, nullptr);
  const std::string parent = tree->parent, child = tree->child;

  RunResult accept = RunCli("link " + Quote(file) + " " + parent + " " + child + " --accept");
  ASSERT_EQ(accept.status, 0) << accept.output;
  EXPECT_NE(accept.output.find("accepted the link " + parent + " -> " + child), std::string::npos) << accept.output;
  auto decision = [&](bool* accepted, bool* rejected) {
    Expected<io::Project> p = io::LoadProject(file);
    ASSERT_TRUE(p.ok());
    *accepted = *rejected = false;
    for (const io::LinkRecord& l : p->links)
      if (l.parent == parent && l.child == child) *accepted |= l.user_accepted, *rejected |= l.user_rejected;
  };
  bool accepted = false, rejected = false;
  decision(&accepted, &rejected);
  EXPECT_TRUE(accepted);
  EXPECT_FALSE(rejected);
  ASSERT_EQ(RunCli("register " + Quote(file)).status, 0);
  decision(&accepted, &rejected);
  EXPECT_TRUE(accepted) << "the next registration dropped the user's decision";

  ASSERT_EQ(RunCli("link " + Quote(file) + " " + parent + " " + child + " --reject").status, 0);
  decision(&accepted, &rejected);
  EXPECT_FALSE(accepted);
  EXPECT_TRUE(rejected);
  ASSERT_EQ(RunCli("link " + Quote(file) + " " + parent + " " + child + " --clear").status, 0);
  decision(&accepted, &rejected);
  EXPECT_FALSE(accepted || rejected);

  RunResult unknown = RunCli("link " + Quote(file) + " " + parent + " nosuchscan --accept");
  EXPECT_NE(unknown.status, 0);
  EXPECT_NE(unknown.output.find("'nosuchscan' is not a scan of the project"), std::string::npos) << unknown.output;
  RunResult reversed = RunCli("link " + Quote(file) + " " + child + " " + parent + " --accept");
  EXPECT_NE(reversed.status, 0);
  EXPECT_NE(reversed.output.find("no link " + child + " -> " + parent), std::string::npos) << reversed.output;
  RunResult two = RunCli("link " + Quote(file) + " " + parent + " " + child + " --accept --reject");
  EXPECT_NE(two.status, 0);
  EXPECT_NE(two.output.find("one of --accept, --reject, --clear"), std::string::npos) << two.output;
}

}  // namespace
}  // namespace scanreg
