#include "core/io/ply.h"

#include <gtest/gtest.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <array>
#include <map>
#include <set>

#include "core/io/pose_file.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakePose;
using test::MakeRoomScan;
using test::TempDir;
using test::WriteBytes;

const std::map<std::string, std::size_t> kBunnyCounts = {
    {"bun000", 40256}, {"bun045", 40097}, {"bun090", 30379},   {"bun180", 40251}, {"bun270", 31701},
    {"bun315", 35336}, {"chin", 37738},   {"ear_back", 32193}, {"top2", 38298},   {"top3", 36023}};

TEST(Ply, ReadsTheTenStanfordRangeImages) {
  SCANREG_REQUIRE_REALDATA(data);
  NullProgress progress;
  CancelToken cancel;
  for (const auto& [name, count] : kBunnyCounts) {
    Expected<Scan> scan = ReadPly(data / "stanford_bunny" / (name + ".ply"), progress, cancel);
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    EXPECT_EQ(scan->name, name);
    EXPECT_EQ(scan->rows, 400) << name;
    EXPECT_EQ(scan->cols, 512) << name;
    EXPECT_EQ(scan->CountValid(), count) << name;
    EXPECT_TRUE(scan->angles.empty()) << name;  // triangulation grid: no spherical angles
    EXPECT_TRUE(scan->world_from_scan.matrix().isIdentity());
    // Row 0 is the top of the image: the vertical axis y falls as the row index grows.
    double n = 0, sr = 0, sy = 0, srr = 0, syy = 0, sry = 0;
    for (int r = 0; r < scan->rows; ++r)
      for (int c = 0; c < scan->cols; ++c) {
        if (!scan->IsValid(r, c)) continue;
        const double y = scan->Point(r, c).y();
        n += 1, sr += r, sy += y, srr += double(r) * r, syy += y * y, sry += r * y;
      }
    const double corr = (n * sry - sr * sy) / std::sqrt((n * srr - sr * sr) * (n * syy - sy * sy));
    EXPECT_LT(corr, -0.95) << name;
  }
}

// Nearest-neighbour distances from the points of `moving` to those of `fixed`, both in world.
std::vector<float> NearestDistances(const Scan& fixed, const Eigen::Isometry3d& fixed_pose, const Scan& moving,
                                    const Eigen::Isometry3d& moving_pose) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t i = 0; i < fixed.size(); ++i) {
    if (!fixed.valid[i]) continue;
    const Eigen::Vector3f p = (fixed_pose * fixed.points[i].cast<double>()).cast<float>();
    cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  std::vector<int> index(1);
  std::vector<float> sq(1);
  std::vector<float> dist;
  for (std::size_t i = 0; i < moving.size(); ++i) {
    if (!moving.valid[i]) continue;
    const Eigen::Vector3f p = (moving_pose * moving.points[i].cast<double>()).cast<float>();
    tree.nearestKSearch(pcl::PointXYZ(p.x(), p.y(), p.z()), 1, index, sq);
    dist.push_back(std::sqrt(sq[0]));
  }
  return dist;
}

float Median(std::vector<float> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

TEST(Ply, BunConfPosesAlignBun045WithBun000) {
  SCANREG_REQUIRE_REALDATA(data);
  const auto dir = data / "stanford_bunny";
  Expected<std::vector<NamedPose>> poses = ReadBunConf(dir / "bun.conf");
  ASSERT_TRUE(poses.ok()) << poses.error().ToString();
  ASSERT_EQ(poses->size(), 10u);
  std::map<std::string, Eigen::Isometry3d> by_file;
  for (const NamedPose& p : *poses) by_file[p.scan] = p.world_from_scan;
  ASSERT_TRUE(by_file.count("bun000.ply") && by_file.count("bun045.ply"));
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> s000 = ReadPly(dir / "bun000.ply", progress, cancel);
  Expected<Scan> s045 = ReadPly(dir / "bun045.ply", progress, cancel);
  ASSERT_TRUE(s000.ok() && s045.ok());

  const std::vector<float> d = NearestDistances(*s000, by_file["bun000.ply"], *s045, by_file["bun045.ply"]);
  std::vector<float> overlap;  // points of bun045 that see the same surface as bun000
  for (float x : d)
    if (x < 0.003f) overlap.push_back(x);
  ASSERT_GT(overlap.size(), d.size() / 2);
  const float within_1mm =
      float(std::count_if(overlap.begin(), overlap.end(), [](float x) { return x < 0.001f; })) / overlap.size();
  EXPECT_LT(Median(overlap), 0.0005f);
  EXPECT_GT(within_1mm, 0.8f);

  // The naive reading p_world = R(q) p + t does not align: this pins the convention.
  auto naive = [](const Eigen::Isometry3d& t) {
    Eigen::Isometry3d n = t;
    n.linear() = t.linear().transpose();
    return n;
  };
  const std::vector<float> dn =
      NearestDistances(*s000, naive(by_file["bun000.ply"]), *s045, naive(by_file["bun045.ply"]));
  EXPECT_GT(Median(dn), 0.002f);
  std::printf("bun045 -> bun000: overlap %zu of %zu points, median %.3f mm, %.1f%% within 1 mm; naive median %.2f mm\n",
              overlap.size(), d.size(), Median(overlap) * 1e3, within_1mm * 100, Median(dn) * 1e3);
}

TEST(Ply, BinaryRoundTripKeepsGridPoseAndAngles) {
  TempDir dir;
  Scan scan = MakeRoomScan(36, 80, "room");
  scan.world_from_scan = MakePose(2.1, {0.3, 1.0, 0.2}, {500000.25, 4200000.5, 31.75});
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WritePly(dir / "room.ply", scan, progress, cancel).ok());
  Expected<Scan> back = ReadPly(dir / "room.ply", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->rows, scan.rows);
  ASSERT_EQ(back->cols, scan.cols);
  EXPECT_EQ(back->valid, scan.valid);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    ASSERT_EQ(back->points[i], scan.points[i]) << i;  // binary float: exact
    ASSERT_EQ(back->reflectance[i], scan.reflectance[i]);
  }
  EXPECT_TRUE(back->world_from_scan.matrix().isApprox(scan.world_from_scan.matrix(), 1e-15));
  EXPECT_EQ(back->angles.empty(), false);
}

TEST(Ply, AsciiCloudWithoutGridIsOrganized) {
  // 2 deg spherical pattern from the origin at range 3..5 m, elevation -30..+40 deg, with intensity.
  std::string body;
  int n = 0;
  for (int e = -15; e <= 20; ++e)
    for (int a = 0; a < 180; ++a) {
      const double az = (a * 2.0 + 0.3) * M_PI / 180.0, el = (e * 2.0 + 0.1) * M_PI / 180.0;
      const double r = 3.0 + std::fmod(a * 0.37, 2.0);
      body += std::to_string(r * std::cos(el) * std::cos(az)) + " " + std::to_string(r * std::cos(el) * std::sin(az)) +
              " " + std::to_string(r * std::sin(el)) + " " + std::to_string(0.1 + 0.004 * a) + "\n";
      ++n;
    }
  const std::string header = "ply\nformat ascii 1.0\ncomment synthetic\nelement vertex " + std::to_string(n) +
                             "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n"
                             "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
  TempDir dir;
  WriteBytes(dir / "cloud.ply", header + body);
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = ReadPly(dir / "cloud.ply", progress, cancel);
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_GE(scan->CountValid(), std::size_t(0.9 * n));
  EXPECT_LE(scan->CountValid(), std::size_t(n));
  EXPECT_FALSE(scan->angles.empty());
  EXPECT_GE(scan->cols, 180);  // at least the cloud's own azimuth sampling
  float refl_max = 0;
  for (std::size_t i = 0; i < scan->size(); ++i)
    if (scan->valid[i]) refl_max = std::max(refl_max, scan->reflectance[i]);
  EXPECT_NEAR(refl_max, 0.1f + 0.004f * 179, 1e-4);
}

// A 2 x 2 Stanford-style grid in big-endian binary: file row 0 is the bottom.
TEST(Ply, BigEndianRangeGridIsFlippedToTopRowFirst) {
  std::string header =
      "ply\nformat binary_big_endian 1.0\nobj_info num_cols 2\nobj_info num_rows 2\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\nproperty uchar intensity\n"
      "element range_grid 4\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body;
  auto put_be = [&](const void* p, int size) {
    const char* c = static_cast<const char*>(p);
    for (int i = size - 1; i >= 0; --i) body += c[i];
  };
  const float v[3][3] = {{0, -1, 2}, {1, -1, 2}, {0, 1, 2}};  // bottom-left, bottom-right, top-left
  const unsigned char intensity[3] = {255, 0, 51};
  for (int k = 0; k < 3; ++k) {
    for (float x : v[k]) put_be(&x, 4);
    body += static_cast<char>(intensity[k]);
  }
  const int cells[4] = {0, 1, 2, -1};
  for (int k : cells) {
    body += static_cast<char>(k < 0 ? 0 : 1);
    if (k >= 0) put_be(&k, 4);
  }
  TempDir dir;
  WriteBytes(dir / "be.ply", header + body);
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = ReadPly(dir / "be.ply", progress, cancel);
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->CountValid(), 3u);
  EXPECT_TRUE(scan->IsValid(0, 0));
  EXPECT_FALSE(scan->IsValid(0, 1));
  EXPECT_EQ(scan->Point(0, 0), Eigen::Vector3f(0, 1, 2));
  EXPECT_EQ(scan->Point(1, 1), Eigen::Vector3f(1, -1, 2));
  EXPECT_FLOAT_EQ(scan->Reflectance(1, 0), 1.0f);
  EXPECT_FLOAT_EQ(scan->Reflectance(0, 0), 0.2f);
}

// Vertices a range_grid cell does not name first — a second return of a cell, a vertex no cell
// names — are kept as the scan's list, with their intensity; writing such a scan gives every point
// back (as a plain list, organized again on reading).
TEST(Ply, VerticesNoCellTakesAreKeptAsAList) {
  const std::string ply =
      "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 2\nelement vertex 5\n"
      "property float x\nproperty float y\nproperty float z\nproperty float intensity\n"
      "element range_grid 4\nproperty list uchar int vertex_indices\nend_header\n"
      "0 -1 2 0.1\n1 -1 2 0.2\n0 1 2 0.3\n0 -1.5 3 0.4\n5 5 5 0.5\n"
      "2 0 3\n1 1\n1 2\n0\n";
  TempDir dir;
  WriteBytes(dir / "returns.ply", ply);
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = ReadPly(dir / "returns.ply", progress, cancel);
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->CountValid(), 3u);
  ASSERT_EQ(scan->list_points.size(), 2u);
  EXPECT_EQ(scan->list_points[0], Eigen::Vector3f(0, -1.5f, 3));
  EXPECT_EQ(scan->list_points[1], Eigen::Vector3f(5, 5, 5));
  EXPECT_FLOAT_EQ(scan->list_reflectance[0], 0.4f);
  EXPECT_FLOAT_EQ(scan->list_reflectance[1], 0.5f);
  EXPECT_EQ(scan->CountPoints(), 5u);

  Scan room = MakeRoomScan(36, 80, "room");
  for (int k = 0; k < 40; ++k) {
    room.list_points.emplace_back(1.0f + 0.05f * k, 0.5f, -0.2f);
    room.list_reflectance.push_back(0.25f);
  }
  ASSERT_TRUE(WritePly(dir / "listed.ply", room, progress, cancel).ok());
  Expected<Scan> back = ReadPly(dir / "listed.ply", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_EQ(back->CountPoints(), room.CountPoints());
  std::multiset<std::array<float, 3>> written, read;
  room.ForEachPoint([&](const Eigen::Vector3f& p, float) { written.insert({p.x(), p.y(), p.z()}); });
  back->ForEachPoint([&](const Eigen::Vector3f& p, float) { read.insert({p.x(), p.y(), p.z()}); });
  EXPECT_TRUE(written == read);  // identity pose: the doubles hold the floats exactly
}

TEST(Ply, BadFilesNameTheProblem) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::string header =
      "ply\nformat ascii 1.0\nobj_info num_cols 2\nobj_info num_rows 1\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty float z\nelement range_grid 2\nproperty list uchar int vertex_indices\n"
      "end_header\n";  // 11 header lines
  WriteBytes(dir / "nan.ply", header + "1 2 3\n1 nan 3\n1 0\n1 1\n");
  Expected<Scan> r = ReadPly(dir / "nan.ply", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("nan.ply, line 13:"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("vertex 1"), std::string::npos) << r.error().message;

  WriteBytes(dir / "token.ply", header + "1 2 3\n1 x2 3\n1 0\n1 1\n");
  r = ReadPly(dir / "token.ply", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("token.ply, line 13:"), std::string::npos) << r.error().message;

  WriteBytes(dir / "short.ply", header + "1 2 3\n1 2 3\n1 0\n");
  r = ReadPly(dir / "short.ply", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("short.ply, line 15:"), std::string::npos) << r.error().message;

  WriteBytes(dir / "index.ply", header + "1 2 3\n1 2 3\n1 0\n1 7\n");
  r = ReadPly(dir / "index.ply", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("vertex 7"), std::string::npos) << r.error().message;

  WriteBytes(dir / "notply.ply", "hello\n");
  r = ReadPly(dir / "notply.ply", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("not a PLY file"), std::string::npos) << r.error().message;

  // A declared count the file cannot hold is refused before anything is allocated (the fuzz run's
  // 150-byte file declaring 2^30 vertices took 4.2 GB).
  for (const char* format : {"binary_little_endian", "ascii"}) {
    WriteBytes(dir / "bomb.ply", std::string("ply\nformat ") + format +
                                     " 1.0\nelement vertex 1073741824\nproperty float x\nproperty float y\n"
                                     "property float z\nend_header\n" +
                                     std::string(60, '1'));
    r = ReadPly(dir / "bomb.ply", progress, cancel);
    ASSERT_FALSE(r.ok()) << format;
    EXPECT_NE(r.error().message.find("declares 1073741824 'vertex' records"), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("60 follow the header"), std::string::npos) << r.error().message;
  }

  // An unreferenced NaN vertex is harmless in a grid file: its cell is simply not there.
  WriteBytes(dir / "unused_nan.ply", header + "1 2 3\nnan nan nan\n1 0\n0\n");
  r = ReadPly(dir / "unused_nan.ply", progress, cancel);
  ASSERT_TRUE(r.ok()) << r.error().ToString();
  EXPECT_EQ(r->CountValid(), 1u);
}

}  // namespace
}  // namespace scanreg::io
