// One simulated pair with known poses, inspected as the GUI's pair panel does.
#include "core/pipeline/inspect_pair.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

class SimulatedPair : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SimulatedProjectOptions o;
    o.stations = 2;
    o.scanner.cols = 1500;
    o.scanner.rows = 375;
    NullProgress progress;
    CancelToken cancel;
    Expected<std::vector<Scan>> s = SimulateProject(o, progress, cancel);
    ASSERT_TRUE(s.ok()) << s.error().ToString();
    scans_ = new std::vector<Scan>(std::move(*s));
  }
  static void TearDownTestSuite() { delete scans_; }
  static Eigen::Isometry3d Truth() {
    return scans_->at(0).reference_world_from_scan->inverse() * *scans_->at(1).reference_world_from_scan;
  }
  static std::vector<Scan>* scans_;
};
std::vector<Scan>* SimulatedPair::scans_ = nullptr;

// The 3D point of a keypoint's nearest cell.
Eigen::Vector3d KeypointPoint(const Scan& scan, const Keypoint& k) {
  return scan.Point(static_cast<int>(std::lround(k.v)), static_cast<int>(std::lround(k.u))).cast<double>();
}

TEST_F(SimulatedPair, InliersAreTrueCorrespondencesAndTheResultMatchesTheTruth) {
  const Scan& parent = scans_->at(0);
  const Scan& child = scans_->at(1);
  NullProgress progress;
  CancelToken cancel;
  Expected<PairInspection> r = InspectPair(parent, child, RegisterOptions{}, {}, progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const io::LinkRecord& link = r->result.link;
  ASSERT_EQ(link.status, io::LinkStatus::kOk) << link.reason;
  ASSERT_EQ(r->coarse_inlier.size(), r->matches.size());
  EXPECT_EQ(link.matches, static_cast<int>(r->matches.size()));
  // The SIFT matches the coarse step kept (the rest of its inliers are FPFH correspondences).
  EXPECT_EQ(std::count(r->coarse_inlier.begin(), r->coarse_inlier.end(), 1), link.ransac_inliers - link.geometric_inliers);
  ASSERT_GE(link.ransac_inliers, 8);
  // Under the true pose, an inlier's two keypoints see the same surface point; most outliers do not.
  const Eigen::Isometry3d truth = Truth();
  std::vector<double> inlier_gap, outlier_gap;
  for (std::size_t i = 0; i < r->matches.size(); ++i) {
    const Eigen::Vector3d p = KeypointPoint(parent, r->parent_features.keypoints[r->matches[i].query]);
    const Eigen::Vector3d c = KeypointPoint(child, r->child_features.keypoints[r->matches[i].train]);
    (r->coarse_inlier[i] ? inlier_gap : outlier_gap).push_back((p - truth * c).norm());
  }
  std::sort(inlier_gap.begin(), inlier_gap.end());
  EXPECT_LT(inlier_gap[inlier_gap.size() / 2], 0.1);
  if (!outlier_gap.empty()) {
    std::sort(outlier_gap.begin(), outlier_gap.end());
    EXPECT_GT(outlier_gap[outlier_gap.size() / 2], 0.1);
  }
  ASSERT_TRUE(r->reference_error.has_value());
  const PoseError e = ComparePoses(link.parent_from_child, truth);
  EXPECT_NEAR(r->reference_error->position_m, e.position_m, 1e-12);
  EXPECT_LT(e.position_m, 0.005);
  EXPECT_LT(e.angle_rad, 0.02 * M_PI / 180);
  ASSERT_TRUE(r->coarse_reference_error.has_value());
  EXPECT_LT(r->coarse_reference_error->position_m, 0.2);
  // The overlay: each scan's distances to the other; the overlapping ones at the noise level.
  ASSERT_EQ(r->child_points.size(), r->child_distance_m.size());
  ASSERT_EQ(r->parent_points.size(), r->parent_distance_m.size());
  ASSERT_GT(r->child_points.size(), 10000u);
  for (const auto* d : {&r->parent_distance_m, &r->child_distance_m}) {
    std::vector<float> overlapping;
    for (float x : *d)
      if (x >= 0) overlapping.push_back(x);
    ASSERT_GT(overlapping.size(), d->size() / 10);
    std::sort(overlapping.begin(), overlapping.end());
    EXPECT_LT(overlapping[overlapping.size() / 2], 0.02);  // 12 mm range noise
  }
}

TEST_F(SimulatedPair, CancelAndEmptyScansAreErrors) {
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  Expected<PairInspection> r = InspectPair(scans_->at(0), scans_->at(1), RegisterOptions{}, {}, progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kCancelled);
  Scan empty("hollow", 10, 20);
  CancelToken go;
  r = InspectPair(scans_->at(0), empty, RegisterOptions{}, {}, progress, go);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'hollow'"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace scanreg::pipeline
