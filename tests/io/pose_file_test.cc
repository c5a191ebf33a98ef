#include "core/io/pose_file.h"

#include <gtest/gtest.h>

#include "core/common/log.h"

#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakePose;
using test::TempDir;
using test::WriteBytes;

TEST(PoseFile, BunConfConventionIsTransposedRotation) {
  TempDir dir;
  // 90 deg about y: q = (0, sin 45, 0, cos 45). R(q) maps x to -z; the verified convention uses R(q)^T,
  // which maps x to +z.
  WriteBytes(dir / "a.conf", "camera 1 2 3 0 0 0 1\n\nbmesh a.ply 1 2 3 0 0.7071067811865476 0 0.7071067811865476\n");
  Expected<std::vector<NamedPose>> poses = ReadBunConf(dir / "a.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  ASSERT_EQ(poses->size(), 1u);
  EXPECT_EQ((*poses)[0].scan, "a.ply");
  const Eigen::Vector3d p = (*poses)[0].world_from_scan * Eigen::Vector3d(1, 0, 0);
  EXPECT_TRUE(p.isApprox(Eigen::Vector3d(1, 2, 4), 1e-12)) << p.transpose();
}

TEST(PoseFile, RealBunConfHasTenPoses) {
  SCANREG_REQUIRE_REALDATA(data);
  Expected<std::vector<NamedPose>> poses = ReadBunConf(data / "stanford_bunny/bun.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  ASSERT_EQ(poses->size(), 10u);
  EXPECT_EQ((*poses)[0].scan, "bun000.ply");
  EXPECT_TRUE((*poses)[0].world_from_scan.matrix().isIdentity(1e-12));
  EXPECT_EQ((*poses)[9].scan, "ear_back.ply");
}

TEST(PoseFile, BunConfErrorsNameTheLine) {
  TempDir dir;
  WriteBytes(dir / "bad.conf", "camera 0 0 0 0 0 0 1\nbmesh a.ply 0 0 0 0 0 0 1\nbmesh b.ply 0 0 0 0 0 1\n");
  Expected<std::vector<NamedPose>> r = ReadBunConf(dir / "bad.conf");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("bad.conf, line 3:"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("7 numbers"), std::string::npos);

  // Control bytes from the file are escaped in the message (a terminal never sees them raw).
  WriteBytes(dir / "esc.conf", "bmesh a.ply 0 0 \x1b[2J 0 0 0 1\n");
  r = ReadBunConf(dir / "esc.conf");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'\\x1b[2J'"), std::string::npos) << r.error().message;
  EXPECT_EQ(r.error().message.find('\x1b'), std::string::npos);

  WriteBytes(dir / "tok.conf", "bmesh a.ply 0 0 zero 0 0 0 1\n");
  r = ReadBunConf(dir / "tok.conf");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("tok.conf, line 1: 'zero'"), std::string::npos) << r.error().message;

  // The dragon's .conf has a `mesh` line (its reconstruction) beside the scans' `bmesh` lines: skipped,
  // with a warning naming the line.
  std::string warning;
  SetLogHandler([&](LogLevel level, const std::string& m) {
    if (level == LogLevel::kWarning) warning += m;
  });
  WriteBytes(dir / "kw.conf",
             "camera 0 0 0 0 0 0 1\nmesh ../reconstruction/dragon_vrip.ply 0 0 0 0 0 0 1\n"
             "bmesh dragonStandRight_0.ply 1 2 3 0 0 0 1\n");
  r = ReadBunConf(dir / "kw.conf");
  SetLogHandler({});
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r->size(), 1u);
  EXPECT_EQ((*r)[0].scan, "dragonStandRight_0.ply");
  EXPECT_NEAR((*r)[0].world_from_scan.translation().y(), 2.0, 1e-12);
  EXPECT_NE(warning.find("kw.conf, line 2:"), std::string::npos) << warning;
  EXPECT_NE(warning.find("'mesh'"), std::string::npos) << warning;
  warning.clear();
  SetLogHandler([&](LogLevel level, const std::string& m) {
    if (level == LogLevel::kWarning) warning += m;
  });
  WriteBytes(dir / "norm.conf", "bmesh a.ply 0 0 0 0 0 0 1.0000001\nbmesh b.ply 0 0 0 0 0 0 1.955586\n");
  r = ReadBunConf(dir / "norm.conf");
  SetLogHandler({});
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(warning.find("line 1"), std::string::npos) << "rounding is no typo: " << warning;
  EXPECT_NE(warning.find("norm.conf, line 2: the quaternion's norm is 1.95559"), std::string::npos) << warning;
  WriteBytes(dir / "only_mesh.conf", "mesh a.ply 0 0 0 0 0 0 1\n");
  EXPECT_FALSE(ReadBunConf(dir / "only_mesh.conf").ok()) << "no scan pose at all is still an error";

  WriteBytes(dir / "zero.conf", "bmesh a.ply 0 0 0 0 0 0 0\n");
  EXPECT_FALSE(ReadBunConf(dir / "zero.conf").ok());
}

TEST(PoseFile, JsonRoundTrip) {
  TempDir dir;
  std::vector<NamedPose> poses = {{"scan \"01\"", MakePose(0.4, {1, 2, 3}, {512345.125, 5401234.5, 42.0})},
                                  {"scan02", MakePose(-2.9, {0, 0, 1}, {-1.0, 0.5, 0.0})}};
  ASSERT_TRUE(WritePosesJson(dir / "poses.json", poses).ok());
  Expected<std::vector<NamedPose>> back = ReadPosesJson(dir / "poses.json");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ((*back)[i].scan, poses[i].scan);
    EXPECT_TRUE((*back)[i].world_from_scan.matrix().isApprox(poses[i].world_from_scan.matrix(), 1e-15));
  }
  WriteBytes(dir / "v2.json", R"({"version":2,"poses":[]})");
  Expected<std::vector<NamedPose>> r = ReadPosesJson(dir / "v2.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("version 2"), std::string::npos);
  WriteBytes(dir / "bad.json", R"({"version":1,"poses":[{"scan":"a","world_from_scan":[1,0,0]}]})");
  r = ReadPosesJson(dir / "bad.json");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("poses[0]"), std::string::npos);
  WriteBytes(dir / "skew.json",
             R"({"version":1,"poses":[{"scan":"a","world_from_scan":[2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}]})");
  EXPECT_FALSE(ReadPosesJson(dir / "skew.json").ok());
  WriteBytes(dir / "syntax.json", "{\"version\":1,");
  EXPECT_FALSE(ReadPosesJson(dir / "syntax.json").ok());
}

TEST(PoseFile, MatrixTxtRoundTrip) {
  TempDir dir;
  const Eigen::Isometry3d pose = MakePose(1.1, {0.5, -1, 0.25}, {3.5, -7.25, 1e6 + 0.125});
  ASSERT_TRUE(WriteMatrixTxt(dir / "m.txt", pose).ok());
  Expected<Eigen::Isometry3d> back = ReadMatrixTxt(dir / "m.txt");
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_TRUE(back->matrix().isApprox(pose.matrix(), 1e-15));
  // Row-major text: the translation ends the first three lines.
  const std::string text = test::ReadBytes(dir / "m.txt");
  EXPECT_NE(text.find(" 3.5\n"), std::string::npos) << text;

  WriteBytes(dir / "short.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n");
  Expected<Eigen::Isometry3d> r = ReadMatrixTxt(dir / "short.txt");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("short.txt, line 4:"), std::string::npos) << r.error().message;
  WriteBytes(dir / "three.txt", "1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n");
  r = ReadMatrixTxt(dir / "three.txt");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("three.txt, line 2:"), std::string::npos) << r.error().message;
}

}  // namespace
}  // namespace scanreg::io
