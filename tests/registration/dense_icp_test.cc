#include <gtest/gtest.h>

#include <chrono>

#include "core/geometry/transform.h"
#include "core/registration/icp.h"
#include "tests/registration/synthetic_room.h"

namespace scanreg {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kRows = 120, kCols = 360;

Eigen::Isometry3d StationPose(double x, double y, double z, double yaw_deg) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw_deg * kPi / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = Eigen::Vector3d(x, y, z);
  return p;
}

class DenseIcpNoise : public ::testing::TestWithParam<double> {};

TEST_P(DenseIcpNoise, RecoversSmallOffsetInARoom) {
  const double sigma = GetParam();  // range noise, metres
  const auto room = testing::DefaultRoom();
  const auto blocks = testing::DefaultBlocks();
  const Scan parent = testing::CastRoomScan(StationPose(-1.0, 0.0, 1.5, 0.0), kRows, kCols, room, blocks, sigma, 1);
  const Scan child = testing::CastRoomScan(StationPose(1.2, -0.5, 1.3, 25.0), kRows, kCols, room, blocks, sigma, 2);
  const Eigen::Isometry3d truth = parent.world_from_scan.inverse() * child.world_from_scan;
  // Initial guess off by 20 cm and 2°.
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.linear() = Eigen::AngleAxisd(2.0 * kPi / 180.0, Eigen::Vector3d(0.3, -0.2, 1.0).normalized()).toRotationMatrix();
  offset.translation() = Eigen::Vector3d(0.12, -0.12, 0.1).normalized() * 0.2;
  const Eigen::Isometry3d initial = offset * truth;
  NullProgress progress;
  CancelToken cancel;
  const auto t0 = std::chrono::steady_clock::now();
  auto r = DenseIcp(parent, child, initial, DenseIcpOptions{}, progress, cancel);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  const PoseError e = ComparePoses(r->parent_from_child, truth);
  std::printf("    dense ICP, sigma %.0f mm: %.3f mm, %.4f deg, %d iterations, %d correspondences, overlap %.3f, rms %.2f mm, %.0f ms\n",
              sigma * 1e3, e.position_m * 1e3, e.angle_rad * 180.0 / kPi, r->iterations, r->correspondences, r->overlap,
              r->rms_m * 1e3, ms);
  EXPECT_LT(e.position_m, 0.005);
  EXPECT_LT(e.angle_rad * 180.0 / kPi, 0.05);
  EXPECT_TRUE(r->converged);
  EXPECT_GT(r->overlap, 0.8);
}

// Noise-free, and W's scanner noise (12 mm).
INSTANTIATE_TEST_SUITE_P(Sigma, DenseIcpNoise, ::testing::Values(0.0, 0.012));

TEST(DenseIcp, OverlapOfIdenticalAndDistantScans) {
  const Scan scan = testing::CastRoomScan(StationPose(0.0, 0.0, 1.5, 0.0), kRows / 2, kCols / 2,
                                          testing::DefaultRoom(), testing::DefaultBlocks());
  NullProgress progress;
  CancelToken cancel;
  auto same = DenseIcp(scan, scan, Eigen::Isometry3d::Identity(), DenseIcpOptions{}, progress, cancel);
  ASSERT_TRUE(same.ok()) << same.error().ToString();
  EXPECT_GT(same->overlap, 0.99);
  EXPECT_TRUE(same->converged);
  EXPECT_LT(ComparePoses(same->parent_from_child, Eigen::Isometry3d::Identity()).position_m, 1e-6);

  Eigen::Isometry3d far = Eigen::Isometry3d::Identity();
  far.translation() = Eigen::Vector3d(100.0, 0.0, 0.0);
  auto apart = DenseIcp(scan, scan, far, DenseIcpOptions{}, progress, cancel);
  ASSERT_TRUE(apart.ok()) << apart.error().ToString();
  EXPECT_LT(apart->overlap, 0.01);
  EXPECT_FALSE(apart->converged);
  std::printf("    identical: overlap %.4f; 100 m apart: overlap %.4f, converged %d\n", same->overlap, apart->overlap,
              apart->converged);
}

TEST(DenseIcp, CancelAndBadOptions) {
  const Scan scan = testing::CastRoomScan(StationPose(0.0, 0.0, 1.5, 0.0), 30, 90, testing::DefaultRoom(), {});
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  auto r = DenseIcp(scan, scan, Eigen::Isometry3d::Identity(), DenseIcpOptions{}, progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kCancelled);
  DenseIcpOptions bad;
  bad.max_correspondence_schedule_m.clear();
  EXPECT_FALSE(bad.Validate().ok());
  Scan empty("empty", 4, 4);
  CancelToken go;
  auto e = DenseIcp(scan, empty, Eigen::Isometry3d::Identity(), DenseIcpOptions{}, progress, go);
  ASSERT_FALSE(e.ok());
  EXPECT_NE(e.error().message.find("empty"), std::string::npos);
}

}  // namespace
}  // namespace scanreg
