// Issue 15: a simulated street at UTM-sized coordinates with sphere targets on tripods and their
// control points (sigma 2 mm), registered and georeferenced end to end.
#include "core/pipeline/georeference_project.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/io/control_file.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/report/report.h"
#include "tests/support/test_paths.h"

namespace scanreg::pipeline {
namespace {

constexpr double kDeg = M_PI / 180.0;

// Levelled stations (tilt compensator), 2 mm range noise at 0.12° steps (a modern scanner's target
// resolution), 4 spheres, the street turned 30° and moved to E 512 km, N 5401 km.
SimulatedProjectOptions UtmStreet() {
  SimulatedProjectOptions o;
  o.stations = 4;
  o.spacing_m = 8;
  o.scanner.range_noise_m = 0.002;
  o.max_tilt_deg = 0;
  o.sphere_targets = 4;
  o.control_noise_m = 0.002;
  o.seed = o.scanner.seed = o.scene.seed = 5;
  o.control_from_world.linear() = Eigen::AngleAxisd(30 * kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  o.control_from_world.translation() = Eigen::Vector3d(512345.678, 5401234.567, 100.25);
  return o;
}

struct Georeferenced {
  io::Project project;
  std::vector<Scan> scans;
  ProjectRegistration result;
};

class GeoreferenceProjectTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    NullProgress progress;
    CancelToken cancel;
    auto project = WriteSimulatedProject(UtmStreet(), dir_->path(), progress, cancel);
    ASSERT_TRUE(project.ok()) << project.error().message;
    auto control = io::ReadControlFile(dir_->path() / "control.csv");
    ASSERT_TRUE(control.ok()) << control.error().message;
    project->control = *control;
    auto scans = LoadProjectScans(*project, progress, cancel);
    ASSERT_TRUE(scans.ok());
    RegisterOptions options;
    options.georef.levelled_sigma_rad = 0.003 * kDeg;  // 10 arc seconds
    auto result = RegisterProjectScans(*project, *scans, options, progress, cancel);
    ASSERT_TRUE(result.ok()) << result.error().message;
    done_ = new Georeferenced{*project, *scans, *result};
  }
  static void TearDownTestSuite() {
    delete done_;
    delete dir_;
  }
  static test::TempDir* dir_;
  static Georeferenced* done_;
};
test::TempDir* GeoreferenceProjectTest::dir_ = nullptr;
Georeferenced* GeoreferenceProjectTest::done_ = nullptr;

void ExpectScansOnTheTruth(const io::Project& p, double metres, double degrees) {
  for (const io::ProjectScan& s : p.scans) {
    ASSERT_TRUE(s.registered) << s.name;
    const Eigen::Isometry3d e = s.reference_world_from_scan->inverse() * s.world_from_scan;
    EXPECT_LT((s.world_from_scan.translation() - s.reference_world_from_scan->translation()).norm(), metres) << s.name;
    EXPECT_LT(Eigen::AngleAxisd(e.linear()).angle() / kDeg, degrees) << s.name;
  }
}

TEST_F(GeoreferenceProjectTest, EveryScanLandsOnTheTruthInTheControlFrame) {
  ASSERT_NE(done_, nullptr);
  const io::Project& p = done_->project;
  ASSERT_TRUE(done_->result.georeferenced) << done_->result.georef_error;
  ASSERT_TRUE(p.georef.has_value());
  EXPECT_EQ(p.georef->used, 4);
  EXPECT_LE(p.georef->rms_m, 0.003);
  for (const io::ControlResidualRecord& r : p.georef->control) {
    EXPECT_EQ(r.role, "used") << r.name;
    EXPECT_GE(r.observations, 1) << r.name;
    EXPECT_NE(ControlGrade(r, p.georef->tolerance_m), "red") << r.name;
  }
  ExpectScansOnTheTruth(p, 0.005, 0.01);
  // Each target observation carries the control name of the sphere it is and a small residual.
  int named = 0;
  for (const io::TargetRecord& t : p.targets) {
    EXPECT_EQ(t.kind, "sphere");
    EXPECT_GE(t.residual_m, 0.0);
    EXPECT_LT(t.residual_m, 0.005) << t.scan << " " << t.name;
    named += t.name.rfind("T", 0) == 0;
  }
  EXPECT_GE(named, 4);
  // The project file keeps control, targets and residuals, and the poses bit for bit at 5,400 km.
  const auto path = dir_->path() / "saved.scanreg.json";
  ASSERT_TRUE(io::SaveProject(done_->project, path).ok());
  auto back = io::LoadProject(path);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->control.size(), done_->project.control.size());
  for (std::size_t i = 0; i < back->control.size(); ++i)
    EXPECT_EQ(back->control[i].position, done_->project.control[i].position) << "bit for bit at 5,400 km";
  for (std::size_t i = 0; i < back->scans.size(); ++i)
    EXPECT_TRUE(back->scans[i].world_from_scan.isApprox(done_->project.scans[i].world_from_scan, 1e-15));
  ASSERT_EQ(back->targets.size(), done_->project.targets.size());
  ASSERT_TRUE(back->georef.has_value());
  EXPECT_EQ(back->georef->rms_m, done_->project.georef->rms_m);
  EXPECT_EQ(back->georef->control.size(), done_->project.georef->control.size());
}

// A blunder is found and named; too little control leaves the registration as it was, saying why.
TEST_F(GeoreferenceProjectTest, AControlPointFiveCentimetresOffIsFlaggedNotSpread) {
  ASSERT_NE(done_, nullptr);
  io::Project p = done_->project;
  p.control[1].position += Eigen::Vector3d(0.03, 0.0, -0.04);
  RegisterOptions options;
  options.georef.levelled_sigma_rad = 0.003 * kDeg;
  NullProgress progress;
  CancelToken cancel;
  auto r = GeoreferenceProject(p, done_->scans, options, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_TRUE(p.georef.has_value());
  EXPECT_EQ(p.georef->control[1].role, "blunder");
  EXPECT_NEAR(p.georef->control[1].delta.norm(), 0.05, 0.006) << "its check residual shows the 5 cm";
  EXPECT_EQ(ControlGrade(p.georef->control[1], p.georef->tolerance_m), "red");
  for (int k : {0, 2, 3}) {
    EXPECT_EQ(p.georef->control[k].role, "used") << p.georef->control[k].name;
    EXPECT_LE(p.georef->control[k].delta.norm(), 0.003) << p.georef->control[k].name;
  }
  ExpectScansOnTheTruth(p, 0.005, 0.01);
  // The report's control table shows the blunder in red (class "failed") with its role.
  auto page = report::WriteReport(p, dir_->path() / "report", progress, cancel);
  ASSERT_TRUE(page.ok()) << page.error().message;
  std::ifstream in(*page);
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t table = html.find("id=\"control-table\"");
  ASSERT_NE(table, std::string::npos);
  const std::size_t row = html.find("<td>" + p.control[1].name + "</td>", table);
  ASSERT_NE(row, std::string::npos);
  const std::size_t tr = html.rfind("<tr", row);
  EXPECT_NE(html.substr(tr, row - tr).find("failed"), std::string::npos) << html.substr(tr, 200);
  EXPECT_NE(html.find("blunder", row), std::string::npos);

  // A scan the user placed by hand keeps its placement relative to the root: its targets (here
  // moved 3 cm, as if its hand placement were off) do not pull it.
  p = done_->project;
  const int hand = 2, root = p.FindScan(*p.root);
  ASSERT_GE(root, 0);
  p.scans[hand].manual_pose = true;
  p.scans[hand].world_from_scan.translation() += Eigen::Vector3d(0.03, 0, 0);
  const Eigen::Isometry3d placed = p.scans[root].world_from_scan.inverse() * p.scans[hand].world_from_scan;
  r = GeoreferenceProject(p, done_->scans, options, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const Eigen::Isometry3d kept = p.scans[root].world_from_scan.inverse() * p.scans[hand].world_from_scan;
  EXPECT_LT((kept.translation() - placed.translation()).norm(), 0.002) << "the hand placement stays (within the datum's mm)";
  EXPECT_GT((p.scans[hand].world_from_scan.translation() - p.scans[hand].reference_world_from_scan->translation()).norm(),
            0.02)
      << "not pulled back onto the targets";

  p = done_->project;
  p.control.resize(2);
  const io::Project before = p;
  r = GeoreferenceProject(p, done_->scans, options, progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("at least 3 control points"), std::string::npos) << r.error().message;
  EXPECT_FALSE(p.georef.has_value()) << "no residuals that describe other poses";
  for (std::size_t i = 0; i < p.scans.size(); ++i)
    EXPECT_TRUE(p.scans[i].world_from_scan.isApprox(before.scans[i].world_from_scan)) << "poses untouched";
}

}  // namespace
}  // namespace scanreg::pipeline
