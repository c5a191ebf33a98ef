// scanreg-cli report / export-poses / export-clouds end to end on a project registered at its true
// poses, and the man page against `--help`.
#include <gtest/gtest.h>

#include <regex>
#include <set>

#include "core/io/pose_csv.h"
#include "core/io/pose_file.h"
#include "core/io/project.h"
#include "core/io/scan_file.h"
#include "core/pipeline/register_settings.h"
#include "tests/integration/cli_run.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

using test::Quote;
using test::ReadBytes;
using test::RunCli;
using test::RunResult;

// A simulated project whose first two scans are registered at their true poses (the far third
// station is not), saved.
std::filesystem::path TrueProject(const test::TempDir& dir) {
  EXPECT_EQ(RunCli("simulate --stations 2 --size 300x80 --far-station --seed 3 --out " + Quote(dir / "p")).status, 0);
  const auto file = dir / "p" / "project.scanreg.json";
  Expected<io::Project> project = io::LoadProject(file);
  EXPECT_TRUE(project.ok());
  if (!project.ok()) return file;
  for (int i = 0; i < 2; ++i) {
    project->scans[i].world_from_scan = *project->scans[i].reference_world_from_scan;
    project->scans[i].registered = true;
  }
  project->root = project->scans[0].name;
  EXPECT_TRUE(io::SaveProject(*project, file).ok());
  return file;
}

double MaxDifference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

TEST(CliExport, ReportOfAProjectAtTheTruePosesShowsZeroErrors) {
  test::TempDir dir;
  const auto project = TrueProject(dir);
  RunResult r = RunCli("report " + Quote(project) + " --out " + Quote(dir / "report"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("2 of 3 scans registered"), std::string::npos) << r.output;
  const std::string html = ReadBytes(dir / "report" / "index.html");
  const std::string errors = html.substr(std::min(html.find("<table id=\"errors-table\">"), html.size()));
  ASSERT_FALSE(errors.empty());
  // Rows: s01 (root), s02 at its true pose -> 0.0 mm; the far station has none.
  const std::regex row("<tr><td>(s0[12])</td><td>[^<]*</td><td>([0-9.]+)</td>");
  int rows = 0;
  for (auto m = std::sregex_iterator(errors.begin(), errors.end(), row); m != std::sregex_iterator(); ++m, ++rows)
    EXPECT_EQ((*m)[2], "0.0") << (*m)[1];
  EXPECT_EQ(rows, 2);
  EXPECT_TRUE(std::filesystem::exists(dir / "report" / "network.png"));
  // A file where the folder should be, and a missing project: one clear line, non-zero status.
  { std::ofstream(dir / "a_file") << "x"; }
  RunResult onto_file = RunCli("report " + Quote(project) + " --out " + Quote(dir / "a_file"));
  EXPECT_NE(onto_file.status, 0);
  EXPECT_NE(onto_file.output.find("a_file"), std::string::npos) << onto_file.output;
  RunResult missing = RunCli("report " + Quote(dir / "nope.scanreg.json") + " --out " + Quote(dir / "r2"));
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("nope.scanreg.json"), std::string::npos) << missing.output;
  EXPECT_EQ(RunCli("report " + Quote(project)).status, 2) << "--out is required";
}

TEST(CliExport, ExportedPosesReadBackEqualInEveryFormat) {
  test::TempDir dir;
  const auto project_file = TrueProject(dir);
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok());
  const std::string p = Quote(project_file);
  ASSERT_EQ(RunCli("export-poses " + p + " --format csv --out " + Quote(dir / "poses.csv")).status, 0);
  ASSERT_EQ(RunCli("export-poses " + p + " --format json --out " + Quote(dir / "poses.json")).status, 0);
  RunResult txt = RunCli("export-poses " + p + " --format txt --out " + Quote(dir / "txt"));
  ASSERT_EQ(txt.status, 0) << txt.output;
  // The unregistered far station is left out, and named: no identity matrix another program would
  // place at the origin.
  EXPECT_NE(txt.output.find("1 of 3 scans are not registered (s03)"), std::string::npos) << txt.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "txt" / "s03.txt"));
  EXPECT_EQ(ReadBytes(dir / "poses.csv").find("s03"), std::string::npos);
  EXPECT_EQ(ReadBytes(dir / "poses.json").find("s03"), std::string::npos);
  // With --include-unregistered it is listed, flagged, without a pose; the readers skip it.
  RunResult flagged =
      RunCli("export-poses " + p + " --format csv --include-unregistered --out " + Quote(dir / "all.csv"));
  ASSERT_EQ(flagged.status, 0) << flagged.output;
  EXPECT_NE(ReadBytes(dir / "all.csv").find("\ns03,,,,,,,unregistered\n"), std::string::npos)
      << ReadBytes(dir / "all.csv");
  ASSERT_EQ(
      RunCli("export-poses " + p + " --format json --include-unregistered --out " + Quote(dir / "all.json")).status, 0);
  EXPECT_NE(ReadBytes(dir / "all.json").find("{\"scan\": \"s03\", \"status\": \"unregistered\"}"), std::string::npos)
      << ReadBytes(dir / "all.json");
  auto csv = io::ReadPosesCsv(dir / "poses.csv");
  ASSERT_TRUE(csv.ok()) << csv.error().ToString();
  auto json = io::ReadPosesJson(dir / "poses.json");
  ASSERT_TRUE(json.ok()) << json.error().ToString();
  ASSERT_EQ(csv->size(), 2u);
  ASSERT_EQ(json->size(), 2u);
  for (const char* name : {"all.csv", "all.json"}) {
    auto all = std::string(name) == "all.csv" ? io::ReadPosesCsv(dir / name) : io::ReadPosesJson(dir / name);
    ASSERT_TRUE(all.ok()) << all.error().ToString();
    EXPECT_EQ(all->size(), 2u) << name;
  }
  for (int i = 0; i < 2; ++i) {
    const io::ProjectScan& s = project->scans[i];
    EXPECT_EQ((*csv)[i].scan, s.name);
    EXPECT_LT(MaxDifference((*csv)[i].world_from_scan, s.world_from_scan), 1e-12) << s.name;
    EXPECT_LT(MaxDifference((*json)[i].world_from_scan, s.world_from_scan), 1e-12) << s.name;
    auto m = io::ReadMatrixTxt(dir / "txt" / (s.name + ".txt"));
    ASSERT_TRUE(m.ok()) << m.error().ToString();
    EXPECT_LT(MaxDifference(*m, s.world_from_scan), 1e-12) << s.name;
  }
  EXPECT_LT(MaxDifference((*csv)[1].world_from_scan, *project->scans[1].reference_world_from_scan), 1e-12);
  EXPECT_EQ(RunCli("export-poses " + p + " --format xml --out " + Quote(dir / "x")).status, 2);
}

TEST(CliExport, ExportCloudsWritesRegisteredScansAndSkipsTheOthers) {
  test::TempDir dir;
  const auto project_file = TrueProject(dir);
  RunResult r =
      RunCli("export-clouds " + Quote(project_file) + " --format ply --apply-poses --out " + Quote(dir / "c"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("skipped s03"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("exported 2 of 3 scans"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "c" / "s03.ply"));
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok());
  NullProgress progress;
  CancelToken cancel;
  auto original = io::ReadScanFile(project->scans[1].path, progress, cancel);
  auto applied = io::ReadScanFile(dir / "c" / "s02.ply", progress, cancel);
  ASSERT_TRUE(original.ok() && applied.ok());
  const Scan& o = (*original)[0];
  const Scan& a = (*applied)[0];
  ASSERT_EQ(a.size(), o.size());
  const Eigen::Isometry3d truth = *project->scans[1].reference_world_from_scan;
  double worst = 0;
  for (std::size_t k = 0; k < o.size(); ++k)
    if (o.valid[k])
      worst =
          std::max(worst, (a.world_from_scan * a.points[k].cast<double>() - truth * o.points[k].cast<double>()).norm());
  EXPECT_LT(worst, 1e-4) << "metres from where the true pose puts the points";
  RunResult bad = RunCli("export-clouds " + Quote(project_file) + " --format xyz --out " + Quote(dir / "d"));
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.output.find("ptx, e57, ply or las"), std::string::npos) << bad.output;
}

// No command writes over a file it reads: each refuses (status 2, both files named) before any
// work, and the input is byte for byte as it was.
TEST(CliExport, OutputsNeverReplaceInputs) {
  test::TempDir dir;
  const auto project_file = TrueProject(dir);
  const auto scan = dir / "p" / "s01.ptx";
  const std::string project_bytes = ReadBytes(project_file), scan_bytes = ReadBytes(scan);
  const std::string p = Quote(project_file);
  const std::vector<std::string> commands = {
      "merge " + p + " --voxel 0.2 --out " + Quote(dir / "p" / "s01.ptx"),  // wrong extension: refused first
      "merge " + p + " --voxel 0.2 --out " + Quote(dir / "m.ply") + " --points " + Quote(project_file),
      "export-poses " + p + " --format json --out " + p,
      "new " + Quote(scan) + " " + Quote(scan),
      "new " + Quote(scan) + " " + Quote(dir / "p" / "s02.ptx"),  // the project name forgotten
      "new " + p + " " + Quote(dir / "p" / "s02.ptx"),            // an existing project

      "convert " + Quote(scan) + " " + Quote(dir / "p" / ".." / "p" / "s01.ptx"),
  };
  for (const std::string& c : commands) {
    RunResult r = RunCli(c);
    SCOPED_TRACE(c);
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_EQ(ReadBytes(project_file), project_bytes);
    EXPECT_EQ(ReadBytes(scan), scan_bytes);
  }
  RunResult refused = RunCli("export-poses " + p + " --format csv --out " + Quote(dir / "p" / "s01.ptx"));
  EXPECT_EQ(refused.status, 2);
  EXPECT_NE(refused.output.find("is the input file"), std::string::npos) << refused.output;
  EXPECT_EQ(ReadBytes(scan), scan_bytes);
  RunResult onto_project = RunCli("export-poses " + p + " --format json --out " + p);
  EXPECT_NE(onto_project.output.find("is the input file"), std::string::npos) << onto_project.output;
  EXPECT_EQ(ReadBytes(project_file), project_bytes);
}

// `info` compares poses with the reference relative to the root, as `register` and `report` do:
// a registration in the root's own frame (root at the identity) shows zero error.
TEST(CliExport, InfoReferenceErrorsAreRelativeToTheRoot) {
  test::TempDir dir;
  const auto project_file = TrueProject(dir);
  Expected<io::Project> project = io::LoadProject(project_file);
  ASSERT_TRUE(project.ok());
  const Eigen::Isometry3d root_ref = *project->scans[0].reference_world_from_scan;
  ASSERT_GT(root_ref.translation().norm() + Eigen::AngleAxisd(root_ref.linear()).angle(), 1e-3);
  for (int i = 0; i < 2; ++i)
    project->scans[i].world_from_scan = root_ref.inverse() * *project->scans[i].reference_world_from_scan;
  ASSERT_TRUE(io::SaveProject(*project, project_file).ok());
  RunResult info = RunCli("info " + Quote(project_file));
  ASSERT_EQ(info.status, 0) << info.output;
  const std::regex row("\n(s0[12]) .* (\\S+) mm, (\\S+)°");
  int rows = 0;
  for (auto m = std::sregex_iterator(info.output.begin(), info.output.end(), row); m != std::sregex_iterator(); ++m) {
    ++rows;
    EXPECT_EQ((*m)[2], "0.0") << (*m)[1] << "\n" << info.output;
    EXPECT_EQ((*m)[3], "0.0000") << (*m)[1];
  }
  EXPECT_EQ(rows, 2) << info.output;
}

// Every command of `scanreg-cli --help` has a section in the man page, and every option of each
// command's --help is described there.
TEST(CliExport, ManPageListsEveryCommandAndOption) {
  const std::string man = ReadBytes(SCANREG_MAN_PAGE);
  ASSERT_FALSE(man.empty()) << SCANREG_MAN_PAGE;
  const auto roff = [](std::string s) { return std::regex_replace(s, std::regex("-"), "\\-"); };
  RunResult help = RunCli("--help");
  ASSERT_EQ(help.status, 0);
  const std::string commands = help.output.substr(help.output.find("commands:"));
  const std::regex command_line("\n  ([a-z][a-z0-9-]*) ");
  int count = 0;
  for (auto m = std::sregex_iterator(commands.begin(), commands.end(), command_line); m != std::sregex_iterator();
       ++m, ++count) {
    const std::string name = (*m)[1];
    EXPECT_NE(man.find(".SS " + roff(name)), std::string::npos) << "man page has no section for " << name;
    RunResult options = RunCli(name + " --help");
    EXPECT_EQ(options.status, 0) << name;
    const std::regex option("\n  --([a-z][a-z0-9-]*)");
    for (auto o = std::sregex_iterator(options.output.begin(), options.output.end(), option);
         o != std::sregex_iterator(); ++o) {
      const std::string opt = (*o)[1];
      if (opt == "help") continue;
      EXPECT_NE(man.find("\\-\\-" + roff(opt)), std::string::npos) << "man page lacks " << name << " --" << opt;
    }
  }
  EXPECT_GE(count, 10) << help.output;
}

// Every registration setting (the GUI's Settings dialog) can be given to `register` as its flag.
TEST(CliExport, RegisterTakesEverySettingAsAFlag) {
  RunResult help = RunCli("register --help");
  ASSERT_EQ(help.status, 0);
  int count = 0;
  for (const pipeline::RegisterSetting& s : pipeline::RegisterSettings()) {
    ++count;
    EXPECT_NE(help.output.find("--" + std::string(s.flag) + " "), std::string::npos) << "register lacks --" << s.flag;
  }
  EXPECT_GE(count, 12);
}

}  // namespace
}  // namespace scanreg
