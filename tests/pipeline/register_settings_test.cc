// Registration settings as project data: options <-> settings round trip, errors that name the
// setting, the pose-based default for imported projects, and imported poses kept as anchors.
#include "core/pipeline/register_settings.h"

#include <gtest/gtest.h>

#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {
namespace {

TEST(RegisterSettings, EveryOptionRoundTripsThroughTheProjectSettings) {
  RegisterOptions options;
  options.from_current_poses = true;
  options.fine = FineMethod::kEm;
  options.match.ratio = 0.7;
  options.range_sigma_m = 0.0005;
  options.overlap_distance_m = 0.01;
  options.global = false;
  options.keep_imported = true;
  options.geometric.coarse_scale = 3.0;
  options.sift.half_size_max_step_deg = 0.25;
  std::map<std::string, std::string> settings{{"simulated.seed", "3"}};
  StoreRegisterSettings(options, &settings);
  EXPECT_EQ(settings.at("register.coarse"), "none");
  EXPECT_EQ(std::stod(settings.at("register.noise_m")), 0.0005);
  EXPECT_EQ(settings.at("simulated.seed"), "3");
  Expected<RegisterOptions> back = RegisterOptionsFromSettings(settings);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_TRUE(back->from_current_poses);
  EXPECT_EQ(back->fine, FineMethod::kEm);
  EXPECT_EQ(back->match.ratio, 0.7);
  EXPECT_EQ(back->range_sigma_m, 0.0005);
  EXPECT_EQ(back->overlap_distance_m, 0.01);
  EXPECT_FALSE(back->global);
  EXPECT_TRUE(back->keep_imported);
  EXPECT_EQ(back->geometric.coarse_scale, 3.0);
  EXPECT_EQ(back->sift.half_size_max_step_deg, 0.25);
  // Every setting's value, applied to the defaults, gives the value back.
  for (const RegisterSetting& s : RegisterSettings()) {
    RegisterOptions fresh;
    ASSERT_TRUE(ApplyRegisterSetting(s, RegisterSettingValue(options, s), &fresh).ok()) << s.key;
    EXPECT_EQ(RegisterSettingValue(fresh, s), RegisterSettingValue(options, s)) << s.key;
  }
  settings["register.coarse"] = "epnp";
  back = RegisterOptionsFromSettings(settings);
  ASSERT_TRUE(back.ok());
  EXPECT_FALSE(back->from_current_poses);
  EXPECT_EQ(back->coarse.method, CoarseMethod::kEpnp);
}

TEST(RegisterSettings, BadValuesNameTheSettingNotAFlag) {
  std::map<std::string, std::string> settings{{"register.fine", "magic"}};
  Expected<RegisterOptions> r = RegisterOptionsFromSettings(settings);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("fine method: 'magic'"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("projective-icp"), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find("--"), std::string::npos) << r.error().message;
  settings = {{"register.noise_m", "1e309"}};
  EXPECT_FALSE(RegisterOptionsFromSettings(settings).ok());
  settings = {{"register.ratio", "0.9x"}};
  EXPECT_FALSE(RegisterOptionsFromSettings(settings).ok());
  settings = {{"register.sift_half_size_step_deg", "-0.1"}};
  EXPECT_FALSE(RegisterOptionsFromSettings(settings).ok());
  settings = {{"register.colour", "red"}};
  r = RegisterOptionsFromSettings(settings);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("register.colour"), std::string::npos);
}

TEST(RegisterSettings, ProjectsOfImportedPosesRefineFromThemByDefault) {
  io::Project project;
  project.scans.resize(2);
  for (io::ProjectScan& s : project.scans) s.registered = s.imported_pose = true;
  Expected<RegisterOptions> o = ProjectRegisterOptions(project);
  ASSERT_TRUE(o.ok());
  EXPECT_TRUE(o->from_current_poses);
  project.settings["register.coarse"] = "3d";  // the user's saved choice wins
  EXPECT_FALSE(ProjectRegisterOptions(project)->from_current_poses);
  project.settings.clear();
  project.scans[1].imported_pose = false;  // one scan without an imported pose: features
  EXPECT_FALSE(ProjectRegisterOptions(project)->from_current_poses);
}

Eigen::Isometry3d Pose(double x, double y, double yaw) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, 0.5);
  return t;
}

// Chain 0 <- 1 <- 2 <- 3 where 0 and 2 are imported: each scan keeps its pose relative to its
// nearest imported ancestor as registered, and the imported scans keep their poses.
TEST(KeepImportedPoses, ScansArePlacedFromTheirNearestImportedAncestor) {
  io::Project project;
  project.scans.resize(4);
  const Eigen::Isometry3d imported0 = Pose(500000, 5000000, 0.2), imported2 = Pose(500020, 5000003, 0.25);
  project.scans[0].world_from_scan = imported0;
  project.scans[2].world_from_scan = imported2;
  ProjectRegistration result;
  result.root = 0;
  const Eigen::Isometry3d estimated[4] = {Pose(500000, 5000000, 0.2), Pose(500010, 5000001, 0.21),
                                          Pose(500020.03, 5000003.01, 0.2502), Pose(500030, 5000004, 0.3)};
  for (int i = 0; i < 4; ++i) {
    ScanRegistration s;
    s.registered = true;
    s.parent = i - 1;
    s.world_from_scan = estimated[i];
    result.scans.push_back(s);
  }
  result.scans[3].registered = false;  // an unregistered scan stays so
  KeepImportedPoses(project, {true, false, true, false}, &result);
  EXPECT_EQ(result.scans[0].world_from_scan.matrix(), imported0.matrix());
  EXPECT_EQ(result.scans[2].world_from_scan.matrix(), imported2.matrix());
  const Eigen::Isometry3d rel1 = imported0.inverse() * result.scans[1].world_from_scan;
  EXPECT_LT((rel1.matrix() - (estimated[0].inverse() * estimated[1]).matrix()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_FALSE(result.scans[3].registered);
  EXPECT_EQ(result.scans[3].world_from_scan.matrix(), estimated[3].matrix());
}

}  // namespace
}  // namespace scanreg::pipeline
