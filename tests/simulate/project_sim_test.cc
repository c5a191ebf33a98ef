#include "core/simulate/project_sim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace scanreg {
namespace {

TEST(SimProjectTest, OptionsValidateRejectsNonsense) {
  EXPECT_TRUE(SimulatedProjectOptions().Validate().ok());
  SimulatedProjectOptions o;
  o.stations = 0;
  EXPECT_FALSE(o.Validate().ok());
  EXPECT_NE(o.Validate().error().message.find("stations"), std::string::npos);
  o = SimulatedProjectOptions();
  o.spacing_m = -5;
  EXPECT_FALSE(o.Validate().ok());
  o = SimulatedProjectOptions();
  o.scanner.cols = 0;  // nested options are validated too
  EXPECT_FALSE(o.Validate().ok());
  NullProgress progress;
  CancelToken cancel;
  o = SimulatedProjectOptions();
  o.stations = 0;
  const auto scans = SimulateProject(o, progress, cancel);
  ASSERT_FALSE(scans.ok());
  EXPECT_EQ(scans.error().code, ErrorCode::kInvalidArgument);
}

TEST(SimProjectTest, StationsAreSpacedAlongTheStreetUprightWithRandomHeadings) {
  SimulatedProjectOptions o;
  const auto poses = SimulatedStationPoses(o);
  ASSERT_EQ(poses.size(), 11u);
  double sum = 0, sin_sum = 0, cos_sum = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Vector3d t = poses[i].translation();
    EXPECT_GE(t.z(), 1.5);
    EXPECT_LE(t.z(), 2.0);
    EXPECT_LE(std::abs(t.y()), 1.5);
    const double tilt = std::acos(std::clamp((poses[i].linear() * Eigen::Vector3d::UnitZ()).z(), -1.0, 1.0));
    EXPECT_LE(tilt, o.max_tilt_deg * M_PI / 180.0 + 1e-9);
    const Eigen::Vector3d x_axis = poses[i].linear().col(0);
    sin_sum += x_axis.y() / x_axis.head<2>().norm();
    cos_sum += x_axis.x() / x_axis.head<2>().norm();
    if (i == 0) continue;
    const double d = (t - poses[i - 1].translation()).norm();
    EXPECT_GT(d, 0.6 * o.spacing_m);
    EXPECT_LT(d, 1.4 * o.spacing_m);
    EXPECT_GT(t.x(), poses[i - 1].translation().x());
    sum += d;
  }
  EXPECT_NEAR(sum / 10.0, o.spacing_m, 0.15 * o.spacing_m);
  // Headings spread over the circle: the mean resultant length of 11 uniform angles is small.
  EXPECT_LT(std::hypot(sin_sum, cos_sum) / 11.0, 0.7);
}

TEST(SimProjectTest, FarStationSharesNoOverlap) {
  SimulatedProjectOptions o;
  o.stations = 3;
  o.scanner.cols = 360;
  o.scanner.rows = 90;
  o.add_far_station = true;
  NullProgress progress;
  CancelToken cancel;
  auto scans = SimulateProject(o, progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  ASSERT_EQ(scans->size(), 4u);
  const auto poses = SimulatedStationPoses(o);
  Eigen::AlignedBox3d street;
  street.setEmpty();
  for (std::size_t i = 0; i < scans->size(); ++i) {
    const Scan& s = (*scans)[i];
    EXPECT_EQ(s.name, "s0" + std::to_string(i + 1));
    EXPECT_TRUE(s.world_from_scan.isApprox(Eigen::Isometry3d::Identity()));
    ASSERT_TRUE(s.reference_world_from_scan.has_value());
    EXPECT_TRUE(s.reference_world_from_scan->isApprox(poses[i]));
    EXPECT_GT(s.CountValid(), s.size() / 4) << s.name;
    if (i + 1 == scans->size()) continue;
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k]) street.extend(*s.reference_world_from_scan * s.points[k].cast<double>());
  }
  const Scan& far = scans->back();
  EXPECT_GT((far.reference_world_from_scan->translation() - poses[0].translation()).norm(), 500.0);
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < far.size(); ++k)
    if (far.valid[k])
      nearest = std::min(nearest, street.exteriorDistance(*far.reference_world_from_scan * far.points[k].cast<double>()));
  EXPECT_GT(nearest, 200.0);
}

TEST(SimProjectTest, CancelledBeforeStart) {
  SimulatedProjectOptions o;
  o.scanner.cols = 100;
  o.scanner.rows = 25;
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  const auto scans = SimulateProject(o, progress, cancel);
  ASSERT_FALSE(scans.ok());
  EXPECT_EQ(scans.error().code, ErrorCode::kCancelled);
}

}  // namespace
}  // namespace scanreg
