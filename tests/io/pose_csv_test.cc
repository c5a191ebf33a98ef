#include "core/io/pose_csv.h"

#include <gtest/gtest.h>

#include "core/geometry/pose_angles.h"
#include "core/geometry/transform.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

Eigen::Isometry3d Pose(double heading_deg, double pitch_deg, double roll_deg, Eigen::Vector3d t) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = RotationFromHeadingPitchRoll({heading_deg * M_PI / 180, pitch_deg * M_PI / 180, roll_deg * M_PI / 180});
  p.translation() = t;
  return p;
}

TEST(PoseCsv, WrittenPosesReadBackEqual) {
  TempDir dir;
  const std::vector<NamedPose> poses = {{"s01", Pose(0, 0, 0, {0, 0, 0})},
                                        {"s,02", Pose(-120.5, 0.3, -0.2, {5.25, -3.125, 0.5})},
                                        {"say \"hi\"", Pose(179.9, -45, 10, {512345.678, 5801234.567, 55.1})}};
  ASSERT_TRUE(WritePosesCsv(dir / "p.csv", poses).ok());
  Expected<std::vector<NamedPose>> back = ReadPosesCsv(dir / "p.csv");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), poses.size());
  for (std::size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ((*back)[i].scan, poses[i].scan);
    const PoseError e = ComparePoses((*back)[i].world_from_scan, poses[i].world_from_scan);
    EXPECT_LT(e.position_m, 1e-9) << poses[i].scan;
    EXPECT_LT(e.angle_rad, 1e-12) << poses[i].scan;
  }
}

TEST(PoseCsv, ColumnsAreThePositionAndTheAnglesInDegrees) {
  TempDir dir;
  ASSERT_TRUE(WritePosesCsv(dir / "p.csv", {{"a", Pose(30, 0, 0, {1, 2, 3})}}).ok());
  std::ifstream in(dir / "p.csv");
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  EXPECT_EQ(header, "scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,status");
  double x, y, z, h, p, r;
  ASSERT_EQ(std::sscanf(row.c_str(), "a,%lf,%lf,%lf,%lf,%lf,%lf", &x, &y, &z, &h, &p, &r), 6) << row;
  EXPECT_DOUBLE_EQ(x, 1);
  EXPECT_DOUBLE_EQ(z, 3);
  EXPECT_NEAR(h, 30, 1e-9);
  EXPECT_NEAR(p, 0, 1e-9);
}

TEST(PoseCsv, StatusColumnRoundTripsAndUnregisteredRowsCarryNoPose) {
  TempDir dir;
  NamedPose a{"s01", Eigen::Isometry3d::Identity(), "imported"};
  a.world_from_scan.translation() = Eigen::Vector3d(500000.125, 5000000.25, 99.5);
  const NamedPose b{"s02", Eigen::Isometry3d::Identity(), kUnregisteredStatus};
  ASSERT_TRUE(WritePosesCsv(dir / "p.csv", {a, b}).ok());
  const std::string text = ReadBytes(dir / "p.csv");
  EXPECT_NE(text.find("s02,,,,,,,unregistered\n"), std::string::npos) << text;
  Expected<std::vector<NamedPose>> back = ReadPosesCsv(dir / "p.csv");
  ASSERT_TRUE(back.ok()) << back.error().message;
  ASSERT_EQ(back->size(), 1u);
  EXPECT_EQ((*back)[0].status, "imported");
  EXPECT_EQ((*back)[0].world_from_scan.translation(), a.world_from_scan.translation());
  // Files written before the status column are still read.
  WriteBytes(dir / "old.csv", "scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg\ns01,1,2,3,0,0,0\n");
  Expected<std::vector<NamedPose>> old = ReadPosesCsv(dir / "old.csv");
  ASSERT_TRUE(old.ok()) << old.error().message;
  EXPECT_EQ((*old)[0].world_from_scan.translation(), Eigen::Vector3d(1, 2, 3));
}

TEST(PoseCsv, MalformedFilesNameTheLine) {
  TempDir dir;
  WriteBytes(dir / "noheader.csv", "s01,0,0,0,0,0,0\n");
  Expected<std::vector<NamedPose>> a = ReadPosesCsv(dir / "noheader.csv");
  ASSERT_FALSE(a.ok());
  EXPECT_NE(a.error().message.find("line 1"), std::string::npos) << a.error().message;
  WriteBytes(dir / "short.csv", "scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg\ns01,0,0,0,0,0,0\ns02,1,2\n");
  Expected<std::vector<NamedPose>> b = ReadPosesCsv(dir / "short.csv");
  ASSERT_FALSE(b.ok());
  EXPECT_NE(b.error().message.find("line 3"), std::string::npos) << b.error().message;
  EXPECT_FALSE(ReadPosesCsv(dir / "missing.csv").ok());
}

}  // namespace
}  // namespace scanreg::io
