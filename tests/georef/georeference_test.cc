#include "core/georef/georeference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace scanreg::georef {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A street of 8 stations 10 m apart at UTM-sized coordinates with 6 sphere targets, 4 of them
// control points (sigma 2 mm). The registration (in the first scan's frame) drifts by a few
// millimetres per link, as a chain does; target centres carry 1 mm noise.
struct Survey {
  std::vector<Eigen::Isometry3d> truth;       // control frame
  std::vector<Eigen::Isometry3d> registered;  // registration frame
  std::vector<ScanLink> links;
  std::vector<TargetObservation> observations;
  std::vector<io::ControlPoint> control;
  std::vector<Eigen::Vector3d> targets;  // control frame
};

Eigen::Isometry3d Pose(double x, double y, double z, double heading, double tilt_x = 0, double tilt_y = 0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, y, z);
  p.linear() = (Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()) *
                Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()))
                   .toRotationMatrix();
  return p;
}

Eigen::Isometry3d Jitter(std::mt19937& rng, double sigma_t, double sigma_r) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Pose(sigma_t * n(rng), sigma_t * n(rng), sigma_t * n(rng), sigma_r * n(rng), sigma_r * n(rng), sigma_r * n(rng));
}

// levelled: the stations stand upright (a tilt compensator levelled them), as GeorefOptions::
// levelled_sigma_rad states; otherwise each is tilted by up to 0.2°.
Survey MakeSurvey(unsigned seed = 3, bool symmetric = false, bool levelled = true) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Survey s;
  const Eigen::Isometry3d control_from_site = Pose(512345.678, 5401234.567, 98.5, 0.7);
  for (int i = 0; i < 8; ++i)
    s.truth.push_back(control_from_site * Pose(10.0 * i, 0.5 * u(rng), 1.7, M_PI * u(rng), levelled ? 0.0 : 0.0035 * u(rng), levelled ? 0.0 : 0.0035 * u(rng)));
  // Tripods at heights of their own; `symmetric`: heights rising evenly, so that the layout turned
  // end for end (and tipped by 0.4°) is the same constellation.
  const double heights[6] = {1.45, 1.2, 1.62, 1.3, 1.55, 1.25};
  for (int k = 0; k < 6; ++k)
    s.targets.push_back(control_from_site *
                        Eigen::Vector3d(-3.0 + 15.0 * k, k % 2 ? 2.6 : -2.6, symmetric ? 1.2 + 0.1 * k : heights[k]));
  // Registration: the root's frame, a chain whose links are off by ~2 mm / 0.005°.
  Eigen::Isometry3d chain = Eigen::Isometry3d::Identity();
  s.registered.push_back(chain);
  for (int i = 1; i < 8; ++i) {
    const Eigen::Isometry3d measured = s.truth[i - 1].inverse() * s.truth[i] * Jitter(rng, 0.002, 0.005 * kDeg);
    s.links.push_back({i - 1, i, measured});
    chain = chain * measured;
    s.registered.push_back(chain);
  }
  for (int i = 0; i < 8; ++i)
    for (const Eigen::Vector3d& x : s.targets) {
      if ((x - s.truth[i].translation()).norm() > 25.0) continue;
      TargetObservation ob;
      ob.scan = i;
      ob.center = s.truth[i].inverse() * x + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      ob.sigma_m = 0.001;
      s.observations.push_back(ob);
    }
  for (int k : {0, 2, 3, 5}) {
    io::ControlPoint c;
    c.name = "CP" + std::to_string(k + 1);
    c.position = s.targets[k] + 0.002 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    c.sigma_m = 0.002;
    s.control.push_back(c);
  }
  return s;
}

// Scans levelled to 10 arc seconds, as a tilt compensator gives.
GeorefOptions Levelled() {
  GeorefOptions o;
  o.levelled_sigma_rad = 5e-5;
  return o;
}

void ExpectScansWithin(const Survey& s, const GeorefResult& r, double metres, double degrees) {
  ASSERT_EQ(r.world_from_scan.size(), s.truth.size());
  for (std::size_t i = 0; i < s.truth.size(); ++i) {
    const Eigen::Isometry3d e = s.truth[i].inverse() * r.world_from_scan[i];
    EXPECT_LT((r.world_from_scan[i].translation() - s.truth[i].translation()).norm(), metres) << "scan " << i;
    EXPECT_LT(Eigen::AngleAxisd(e.linear()).angle() / kDeg, degrees) << "scan " << i;
  }
}

TEST(Georeference, PlacesTheProjectOnControlAtUtmCoordinates) {
  const Survey s = MakeSurvey();
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->used, 4);
  EXPECT_EQ(r->targets, 6) << "targets seen by several scans are one target each";
  EXPECT_LE(r->rms_m, 0.003);
  for (const ControlResidual& c : r->control) {
    EXPECT_EQ(c.role, ControlRole::kUsed) << c.name;
    EXPECT_GE(c.observations, 2) << c.name;
  }
  ExpectScansWithin(s, *r, 0.005, 0.01);
  // Targets were tied to control by their constellation alone: every observation of a control
  // target carries that control point's name.
  for (std::size_t j = 0; j < s.observations.size(); ++j) {
    const Eigen::Vector3d world = s.truth[s.observations[j].scan] * s.observations[j].center;
    for (const io::ControlPoint& c : s.control) {
      if ((world - c.position).norm() < 0.05) {
        EXPECT_EQ(r->observation_target[j], c.name);
      }
    }
    EXPECT_LT(r->observation_residual_m[j], 0.005);
  }
}

// Without levelling, the roll about the street's axis rests on the control points' spread across it
// (2 mm over 5.2 m: about 0.03°), and a scan 15 m from its targets carries that turn into its
// position: within 1.5 cm and 0.1°, where levelled scans are within 5 mm and 0.01°.
TEST(Georeference, UnlevelledScansAreTiltedByTheControlAlone) {
  const Survey s = MakeSurvey(3, false, false);
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, GeorefOptions{}, cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->used, 4);
  EXPECT_LE(r->rms_m, 0.005) << "2 mm per axis is 3.5 mm in 3D";
  ExpectScansWithin(s, *r, 0.015, 0.1);
}

// Stations tilted by up to 3° whose files give the tilt (the compensator's pitch and roll, to 10"):
// levelled through each file's vertical they are placed as well as upright ones; taken as upright
// (the vertical assumed to be each scan's z axis) they are not.
TEST(Georeference, TiltFromTheFilesPoseLevelsTiltedScans) {
  Survey s = MakeSurvey(5);
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  // Tilt every station about its own axes: the truth, links and observations follow.
  for (Eigen::Isometry3d& t : s.truth) t = t * Pose(0, 0, 0, 0, 0.035 * u(rng), 0.035 * u(rng));
  s.registered.assign(1, Eigen::Isometry3d::Identity());
  for (std::size_t i = 0; i + 1 < s.truth.size(); ++i) {
    s.links[i].parent_from_child = s.truth[i].inverse() * s.truth[i + 1] * Jitter(rng, 0.002, 0.005 * kDeg);
    s.registered.push_back(s.registered.back() * s.links[i].parent_from_child);
  }
  s.observations.clear();
  for (int i = 0; i < static_cast<int>(s.truth.size()); ++i)
    for (const Eigen::Vector3d& x : s.targets) {
      if ((x - s.truth[i].translation()).norm() > 25.0) continue;
      TargetObservation ob;
      ob.scan = i;
      ob.center = s.truth[i].inverse() * x + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      s.observations.push_back(ob);
    }
  std::vector<Eigen::Vector3d> up;
  for (const Eigen::Isometry3d& t : s.truth)
    up.push_back((t.linear().transpose() * Eigen::Vector3d::UnitZ() + 5e-5 * Eigen::Vector3d(n(rng), n(rng), 0)).normalized());
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel, {}, up);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->used, 4);
  EXPECT_LE(r->rms_m, 0.003);
  ExpectScansWithin(s, *r, 0.005, 0.015);
  for (std::size_t i = 0; i < s.truth.size(); ++i) {  // each vertical: 2.5 sigma of the compensator's 10" per axis
    const Eigen::Vector3d truth_up = s.truth[i].linear().transpose() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d placed_up = r->world_from_scan[i].linear().transpose() * Eigen::Vector3d::UnitZ();
    EXPECT_LT(std::acos(std::clamp(truth_up.dot(placed_up), -1.0, 1.0)) / kDeg, 0.01) << "scan " << i;
  }
  // The same scans taken as upright: the levelling fights the control and the scans' tilts.
  auto upright = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  if (upright.ok()) {
    double worst = 0;
    for (std::size_t i = 0; i < s.truth.size(); ++i)
      worst = std::max(worst, Eigen::AngleAxisd((s.truth[i].inverse() * upright->world_from_scan[i]).linear()).angle());
    EXPECT_GT(worst / kDeg, 0.1) << "the file's tilt is what levels these scans";
  }
}

TEST(Georeference, AControlPointFiveCentimetresOffIsNamedAndNotSpread) {
  Survey s = MakeSurvey();
  s.control[2].position += Eigen::Vector3d(0.03, -0.04, 0.0);  // 5 cm
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->control[2].role, ControlRole::kBlunder);
  EXPECT_NEAR(r->control[2].residual_m(), 0.05, 0.005) << "its check residual shows the 5 cm";
  EXPECT_EQ(GradeOf(r->control[2].residual_m(), 0.01), Grade::kRed);
  for (int k : {0, 1, 3}) {
    EXPECT_EQ(r->control[k].role, ControlRole::kUsed) << r->control[k].name;
    EXPECT_LE(r->control[k].residual_m(), 0.003) << r->control[k].name;
  }
  ExpectScansWithin(s, *r, 0.005, 0.01);
}

TEST(Georeference, ACheckPointIsComparedNotUsed) {
  Survey s = MakeSurvey();
  s.control[1].check = true;
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r->used, 3);
  EXPECT_EQ(r->control[1].role, ControlRole::kCheck);
  EXPECT_LT(r->control[1].residual_m(), 0.006);
  EXPECT_GT(r->control[1].residual_m(), 0.0);
  ExpectScansWithin(s, *r, 0.006, 0.01);
}

TEST(Georeference, TooFewControlPointsInTheScansIsAClearError) {
  Survey s = MakeSurvey();
  s.control.resize(2);
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("at least 3 control points"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("0 can place"), std::string::npos) << r.error().message;
  // Control whose constellation is no constellation of targets (stretched by half): none tied.
  s = MakeSurvey();
  const Eigen::Vector3d mid = s.control[0].position;
  for (io::ControlPoint& c : s.control) c.position = mid + 1.5 * (c.position - mid);
  r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  EXPECT_FALSE(r.ok());
}

TEST(Georeference, ASymmetricTargetLayoutIsNotGuessed) {
  Survey s = MakeSurvey(3, true);
  CancelToken cancel;
  auto r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_FALSE(r.ok()) << "tied in one of two ways that fit equally well";
  EXPECT_NE(r.error().message.find("more than one way"), std::string::npos) << r.error().message;
  // Naming one target after its control point settles it.
  for (TargetObservation& ob : s.observations)
    if ((s.truth[ob.scan] * ob.center - s.targets[0]).norm() < 0.05) ob.name = "CP1";
  r = Georeference(s.registered, s.links, s.observations, s.control, Levelled(), cancel);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ExpectScansWithin(s, *r, 0.005, 0.01);
}

TEST(Georeference, ResidualGrades) {
  EXPECT_EQ(GradeOf(0.004, 0.01), Grade::kGreen);
  EXPECT_EQ(GradeOf(0.006, 0.01), Grade::kOrange);
  EXPECT_EQ(GradeOf(0.011, 0.01), Grade::kRed);
}

}  // namespace
}  // namespace scanreg::georef
