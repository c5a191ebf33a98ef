#include "core/io/pcd.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>

#include "core/io/organize_default.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakePose;
using test::MakeRoomScan;
using test::TempDir;

TEST(Pcd, OrganizedKinectFrameKeepsItsGrid) {
  SCANREG_REQUIRE_REALDATA(data);
  const auto path = data / "pcl_test/frame_20121214T142255.814212.pcd";
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = ReadPcd(path, progress, cancel);
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->rows, 480);
  EXPECT_EQ(scan->cols, 640);
  // Ground truth from PCL's own loader: the finite points, cell by cell.
  pcl::PointCloud<pcl::PointXYZ> reference;
  ASSERT_EQ(pcl::io::loadPCDFile(path.string(), reference), 0);
  std::size_t finite = 0, mismatched = 0;
  for (int r = 0; r < 480; ++r)
    for (int c = 0; c < 640; ++c) {
      const auto& p = reference.at(c, r);
      const bool ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
      finite += ok;
      if (ok != scan->IsValid(r, c) || (ok && scan->Point(r, c) != Eigen::Vector3f(p.x, p.y, p.z))) ++mismatched;
    }
  EXPECT_EQ(mismatched, 0u);
  EXPECT_EQ(scan->CountValid(), finite);
  EXPECT_GT(finite, 100000u);
  EXPECT_LT(finite, 307200u);  // NaN cells exist and are empty, not errors
}

TEST(Pcd, UnorganizedCloudWithIntensityIsOrganized) {
  SCANREG_REQUIRE_REALDATA(data);
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = ReadPcd(data / "pcl_test/cturtle.pcd", progress, cancel);
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_GE(scan->CountValid(), std::size_t(0.9 * 167198));
  std::printf("cturtle.pcd: %zu of 167198 points kept in a %d x %d grid\n", scan->CountValid(), scan->rows, scan->cols);
  EXPECT_LE(scan->CountValid(), 167198u);
  EXPECT_FALSE(scan->angles.empty());
  // Intensity is carried over (not the 0.5 default everywhere).
  std::size_t not_default = 0;
  for (std::size_t i = 0; i < scan->size(); ++i) not_default += scan->valid[i] && scan->reflectance[i] != 0.5f;
  EXPECT_GT(not_default, scan->CountValid() / 2);
}

TEST(Pcd, RoundTripKeepsGridAndPose) {
  TempDir dir;
  Scan scan = MakeRoomScan(24, 50, "room");
  scan.world_from_scan = MakePose(0.8, {0, 0.2, 1}, {10.5, -4.25, 1.5});
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WritePcd(dir / "room.pcd", scan, progress, cancel).ok());
  Expected<Scan> back = ReadPcd(dir / "room.pcd", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->rows, 24);
  ASSERT_EQ(back->cols, 50);
  EXPECT_EQ(back->valid, scan.valid);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    ASSERT_EQ(back->points[i], scan.points[i]);
    ASSERT_EQ(back->reflectance[i], scan.reflectance[i]);
  }
  // PCD keeps the viewpoint in single precision.
  EXPECT_LT((back->world_from_scan.translation() - scan.world_from_scan.translation()).norm(), 1e-5);
  EXPECT_TRUE(back->world_from_scan.linear().isApprox(scan.world_from_scan.linear(), 1e-6));
}

TEST(Pcd, MissingAndBrokenFiles) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> r = ReadPcd(dir / "none.pcd", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
  test::WriteBytes(dir / "broken.pcd", "VERSION 0.7\nFIELDS x y\n");
  r = ReadPcd(dir / "broken.pcd", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("broken.pcd"), std::string::npos);
}

// Headers that disagree with themselves or with the file's size are refused before PCL reads the
// data (issue 16: PCL crashed, allocated gigabytes, or returned 0 points with success).
TEST(Pcd, InconsistentHeadersAreNamedBeforePclReadsTheData) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::string fields = "VERSION 0.7\nFIELDS x y z\n";
  const std::string sizes = "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"size.pcd", fields + "SIZE 1.5 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "size.pcd:3: SIZE must be 1, 2, 4 or 8"},
      {"count.pcd", fields + "SIZE 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "3 FIELDS but 2 SIZE"},
      {"points.pcd", fields + sizes + "WIDTH 2\nHEIGHT 2\nPOINTS 3\nDATA ascii\n1 2 3\n", "POINTS 3 is not WIDTH x HEIGHT"},
      {"float2.pcd", fields + "SIZE 2 4 4\nTYPE F F F\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "TYPE F with SIZE 2"},
      {"huge.pcd", fields + sizes + "WIDTH 1073741824\nHEIGHT 1\nPOINTS 1073741824\nDATA binary\n0123456789ab",
       "truncated: the header declares 1073741824 points"},
      {"hugeascii.pcd", fields + sizes + "WIDTH 1000000000\nHEIGHT 1\nPOINTS 1000000000\nDATA ascii\n1 2 3\n",
       "truncated: the header declares 1000000000 points"},
      {"compressed.pcd",
       fields + sizes + "WIDTH 10\nHEIGHT 1\nPOINTS 10\nDATA binary_compressed\n" + std::string("\x04\0\0\0\xff\xff\0\0abcd", 12),
       "unpacks to 65535 bytes, not the 120 bytes"},
      {"noxyz.pcd", "VERSION 0.7\nFIELDS a b c\n" + sizes + "WIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "no x, y, z fields"},
      {"unknown.pcd", fields + sizes + "WIDTH 1\nBOGUS \x01\x02\nDATA ascii\n1 2 3\n", "unknown header entry 'BOGUS'"},
      {"nodata.pcd", fields + sizes + "WIDTH 1\n", "the header ends before its DATA line"},
      {"zero.pcd", fields + sizes + "WIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA ascii\n", "no points"},
      // A viewpoint that is no pose (found by the fuzz test: PCL read these as a non-finite pose).
      {"viewinf.pcd", fields + sizes + "WIDTH 1\nVIEWPOINT 1e309 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "viewinf.pcd:7: VIEWPOINT must be 7 finite numbers"},
      {"viewdash.pcd", fields + sizes + "WIDTH 1\nVIEWPOINT - 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "VIEWPOINT must be 7 finite numbers"},
      {"viewzero.pcd", fields + sizes + "WIDTH 1\nVIEWPOINT 0 0 0 0 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "quaternion that is not zero"},
      {"viewshort.pcd", fields + sizes + "WIDTH 1\nVIEWPOINT 0 0 0 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
       "VIEWPOINT must be 7"},
  };
  for (const Case& c : cases) {
    test::WriteBytes(dir / c.name, c.text);
    Expected<Scan> r = ReadPcd(dir / c.name, progress, cancel);
    ASSERT_FALSE(r.ok()) << c.name << " was accepted";
    EXPECT_EQ(r.error().code, ErrorCode::kParseError) << c.name;
    EXPECT_NE(r.error().message.find(c.expected), std::string::npos) << c.name << ": " << r.error().message;
    EXPECT_NE(r.error().message.find(c.name), std::string::npos) << "names the file: " << r.error().message;
    for (char ch : r.error().message) EXPECT_TRUE(ch >= 32 || ch == '\n') << c.name << ": control byte echoed";
  }
  // A directory is not a PCD file.
  Expected<Scan> r = ReadPcd(dir.path(), progress, cancel);
  ASSERT_FALSE(r.ok());
  // A consistent small ASCII file still reads.
  test::WriteBytes(dir / "ok.pcd", fields + sizes + "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n1 2 3\n4 5 6\n");
  Expected<Scan> ok = ReadPcd(dir / "ok.pcd", progress, cancel);
  ASSERT_TRUE(ok.ok()) << ok.error().ToString();
  EXPECT_EQ(ok->CountValid(), 2u);
}

TEST(OrganizeDefault, StepFollowsPointSpacing) {
  // A regular 0.5 deg pattern over 90 x 30 deg: the estimated spacing is ~0.5 deg.
  std::vector<Eigen::Vector3f> points;
  for (int e = 0; e < 60; ++e)
    for (int a = 0; a < 180; ++a) {
      const double az = (a * 0.5) * M_PI / 180.0, el = (-10 + e * 0.5) * M_PI / 180.0;
      points.emplace_back(5 * std::cos(el) * std::cos(az), 5 * std::cos(el) * std::sin(az), 5 * std::sin(el));
    }
  const double step = DensityAngularStep(points);
  EXPECT_NEAR(step * 180 / M_PI, 0.5, 0.1);
  EXPECT_EQ(DensityAngularStep({Eigen::Vector3f::Zero()}), 0.0);
  Expected<Scan> bad = OrganizeCloudByDensity({Eigen::Vector3f::Zero()}, {}, "z", "z.ply");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("z.ply"), std::string::npos);
}

}  // namespace
}  // namespace scanreg::io
