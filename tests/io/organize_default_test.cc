// Organizing unorganized clouds of the usual sensors (multi-beam lidar, TLS, RGB-D camera) keeps
// nearly every point, in a grid whose neighbouring cells are neighbouring directions.
#include "core/io/organize_default.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/common/log.h"
#include "core/io/pcd.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

constexpr double kDeg = M_PI / 180.0;

using Key = std::array<float, 3>;
Key KeyOf(const Eigen::Vector3f& p) { return {p.x(), p.y(), p.z()}; }

// 69792 -> "69,792", as the warnings write counts.
std::string Count(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), ",");
  return s;
}

double Azimuth(const Eigen::Vector3f& p) { return std::atan2(double(p.y()), double(p.x())); }
double Elevation(const Eigen::Vector3f& p) {
  return std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
}
Eigen::Vector3d Direction(double az, double el) {
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
}

// Known scene around a sensor `height` metres above the floor: the floor and the walls (6 m high)
// of a 43 x 23 m hall, open above. Range along unit direction d, 0 when the ray sees the sky or
// goes beyond max_range.
double RangeInHall(const Eigen::Vector3d& d, double height, double max_range) {
  const Eigen::Vector3d lo(-18.0, -9.0, -height), hi(25.0, 14.0, 6.0 - height);
  double t = 1e9;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12 || (k == 2 && d[k] > 0)) continue;
    t = std::min(t, (d[k] > 0 ? hi[k] : lo[k]) / d[k]);
  }
  if (t > max_range || t * d.z() > hi.z() + 1e-9) return 0.0;
  return t;
}

// A Velodyne HDL-32-like sweep: 32 lasers from -30.67 to +10.67 deg in 4/3 deg steps, a firing
// every 0.16 deg of an unevenly turning head, small angular jitter, 2 % dropped returns; shuffled
// (as an unorganized file). The scanner frame is tilted by tilt_deg about x.
std::vector<Eigen::Vector3f> SimulateHdl32(std::mt19937& rng, double tilt_deg = 0.0) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(tilt_deg * kDeg, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<Eigen::Vector3f> points;
  const int firings = 2250;
  for (int j = 0; j < firings; ++j) {
    const double az0 = -180.0 + 0.16 * j + 0.3 * std::sin(2 * M_PI * j / firings);
    for (int k = 0; k < 32; ++k) {
      const double az = (az0 + 0.0046 * k + 0.003 * noise(rng)) * kDeg;
      const double el = (-30.67 + k * 4.0 / 3.0 + 0.005 * noise(rng)) * kDeg;
      const Eigen::Vector3d d = Direction(az, el);
      const double range = RangeInHall(d, 1.8, 70.0);
      if (range <= 0.0 || uniform(rng) < 0.02) continue;
      points.push_back((tilt * (range * (1.0 + 0.002 * noise(rng)) * d)).cast<float>());
    }
  }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

// A TLS-like regular grid: step_deg both ways over [az0, az1) x [el0, el1), tiny encoder jitter;
// shuffled.
std::vector<Eigen::Vector3f> SimulateTls(std::mt19937& rng, double step_deg, int az0, int az1, int el0, int el1) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Vector3f> points;
  const int cols = static_cast<int>(std::lround((az1 - az0) / step_deg));
  const int rows = static_cast<int>(std::lround((el1 - el0) / step_deg));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector3d d =
          Direction((az0 + c * step_deg + 0.002 * noise(rng)) * kDeg, (el0 + r * step_deg + 0.002 * noise(rng)) * kDeg);
      const double range = RangeInHall(d, 1.5, 200.0);
      if (range > 0.0) points.push_back((range * d).cast<float>());
    }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

// An RGB-D-like frame: a 320 x 240 pinhole camera (f = 285 px, 58 x 46 deg) seeing a slanted wall
// and a box; every pixel has a depth. Camera frame (x right, y down, z forward) when along_x is
// false, else turned so that the optical axis is the scanner's +x.
std::vector<Eigen::Vector3f> SimulateRgbd(std::mt19937& rng, bool along_x) {
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Eigen::Vector3f> points;
  const int w = 320, h = 240;
  const double f = 285.0;
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d ray((u - 0.5 * w + 0.5) / f, (v - 0.5 * h + 0.5) / f, 1.0);
      double depth = 3.0 + 0.8 * ray.y() + 0.3 * ray.x();
      if (std::abs(ray.x() - 0.1) < 0.15 && std::abs(ray.y()) < 0.2) depth = 1.6;
      const Eigen::Vector3d p = depth * (1.0 + 0.003 * noise(rng)) * ray;
      points.push_back((along_x ? Eigen::Vector3d(p.z(), -p.x(), -p.y()) : p).cast<float>());
    }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

// Warnings logged while it lives.
class WarningLog {
 public:
  WarningLog() {
    SetLogHandler([this](LogLevel level, const std::string& message) {
      if (level == LogLevel::kWarning || level == LogLevel::kInfo) messages.push_back(message);
      warnings += level == LogLevel::kWarning;
    });
  }
  ~WarningLog() { SetLogHandler({}); }
  WarningLog(const WarningLog&) = delete;
  WarningLog& operator=(const WarningLog&) = delete;
  std::vector<std::string> messages;  // warnings and information
  int warnings = 0;
};

// Checks what holds for any organized cloud: every kept point is an input point, kept at most as
// often as it occurs; the grid stays within 4 cells per point; each point lies near its cell's
// angles (within its row's half spacing and a few columns) and each row runs in azimuth order.
// Returns the number of points kept.
std::size_t CheckGrid(const Scan& scan, const std::vector<Eigen::Vector3f>& input, int max_shift_cols) {
  std::map<Key, int> left;
  for (const auto& p : input) ++left[KeyOf(p)];
  std::size_t kept = 0;
  EXPECT_TRUE(scan.Validate().ok());
  EXPECT_LE(double(scan.rows) * scan.cols, 4.0 * double(input.size()));
  EXPECT_FALSE(scan.angles.empty());
  if (scan.angles.empty() || scan.cols < 2) return scan.CountValid();
  const double az_step = double(scan.angles.azimuth[1]) - scan.angles.azimuth[0];
  for (int r = 0; r < scan.rows; ++r) {
    const auto& el = scan.angles.elevation;
    double half_row = 0.0;
    if (r > 0) half_row = std::max(half_row, 0.5 * std::abs(double(el[r - 1]) - el[r]));
    if (r + 1 < scan.rows) half_row = std::max(half_row, 0.5 * std::abs(double(el[r + 1]) - el[r]));
    double previous_offset = -1.0;
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      ++kept;
      const Eigen::Vector3f& p = scan.Point(r, c);
      auto it = left.find(KeyOf(p));
      EXPECT_TRUE(it != left.end() && it->second-- > 0) << "cell " << r << "," << c << " holds no input point";
      EXPECT_LE(std::abs(Elevation(p) - el[r]), half_row + 1e-5) << "cell " << r << "," << c;
      const double daz = std::remainder(Azimuth(p) - scan.angles.azimuth[c], 2 * M_PI);
      EXPECT_LE(std::abs(daz), (max_shift_cols + 0.5) * az_step + 1e-6) << "cell " << r << "," << c;
      // Azimuth from column 0 in [0, 2 pi); the first and last columns may hold points across it.
      double offset = Azimuth(p) - scan.angles.azimuth[0];
      offset -= 2 * M_PI * std::floor(offset / (2 * M_PI));
      if (c > max_shift_cols + 1 && c + max_shift_cols + 2 < scan.cols) {
        EXPECT_GE(offset, previous_offset) << "row " << r << " out of azimuth order at column " << c;
        previous_offset = offset;
      }
    }
  }
  return kept;
}

TEST(OrganizeDefault, VelodyneLikeCloudKeepsNearlyAllItsPoints) {
  std::mt19937 rng(11);
  const std::vector<Eigen::Vector3f> points = SimulateHdl32(rng);
  EXPECT_EQ(RingGridOptions(points).row_elevations_rad.size(), 32u);
  WarningLog log;
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "hdl32", "hdl32.pcd");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  // One row per laser, at the laser's elevation (row 0 the highest); the columns at the firing step.
  ASSERT_EQ(scan->rows, 32);
  for (int r = 0; r < 32; ++r) EXPECT_NEAR(scan->angles.elevation[r] / kDeg, -30.67 + (31 - r) * 4.0 / 3.0, 0.01);
  EXPECT_NEAR((scan->angles.azimuth[1] - scan->angles.azimuth[0]) / kDeg, 0.16, 0.002);
  const std::size_t kept = CheckGrid(*scan, points, 1);
  std::printf("HDL-32-like: %zu of %zu points kept in a %d x %d grid\n", kept, points.size(), scan->rows, scan->cols);
  EXPECT_GE(kept, std::size_t(std::ceil(0.99 * points.size())));
  // The points without a cell stay as a list; they are reported, with the count and the file, and a
  // lidar seen from one place keeps its viewpoint.
  EXPECT_EQ(scan->list_points.size(), points.size() - kept);
  EXPECT_TRUE(scan->single_viewpoint);
  if (kept < points.size()) {
    ASSERT_EQ(log.messages.size(), 1u);
    EXPECT_EQ(log.warnings, 0);
    EXPECT_NE(log.messages[0].find("hdl32.pcd"), std::string::npos);
    EXPECT_NE(log.messages[0].find(Count(points.size() - kept) + " of "), std::string::npos);
  }
}

TEST(OrganizeDefault, TiltedVelodyneLikeCloudKeepsNearlyAllItsPoints) {
  // Tilted by 3 deg, the rings overlap in elevation: no ring grid, a uniform one.
  std::mt19937 rng(12);
  const std::vector<Eigen::Vector3f> points = SimulateHdl32(rng, 3.0);
  EXPECT_TRUE(RingGridOptions(points).row_elevations_rad.empty());
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "tilted", "tilted.pcd");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  const std::size_t kept = CheckGrid(*scan, points, 2);
  std::printf("tilted HDL-32-like: %zu of %zu points kept in a %d x %d grid\n", kept, points.size(), scan->rows,
              scan->cols);
  EXPECT_GE(kept, std::size_t(std::ceil(0.99 * points.size())));
}

TEST(OrganizeDefault, TlsLikeRegularGridKeepsNearlyAllItsPoints) {
  // 0.1 deg both ways over 60 x 30 deg, shuffled: one row per scan line, columns over the data's
  // 60 deg only.
  std::mt19937 rng(13);
  const std::vector<Eigen::Vector3f> points = SimulateTls(rng, 0.1, -20, 40, -10, 20);
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "tls", "tls.ply");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_NEAR((scan->angles.azimuth[1] - scan->angles.azimuth[0]) / kDeg, 0.1, 0.001);
  const int mid = scan->rows / 2;
  EXPECT_NEAR((scan->angles.elevation[mid] - scan->angles.elevation[mid + 1]) / kDeg, 0.1, 0.001);
  EXPECT_LE(scan->cols, 602);
  const std::size_t kept = CheckGrid(*scan, points, 1);
  std::printf("TLS-like: %zu of %zu points kept in a %d x %d grid\n", kept, points.size(), scan->rows, scan->cols);
  EXPECT_GE(kept, std::size_t(std::ceil(0.99 * points.size())));
}

TEST(OrganizeDefault, RgbdLikeFrameKeepsNearlyAllItsPoints) {
  for (const bool along_x : {false, true}) {
    SCOPED_TRACE(along_x ? "optical axis along x" : "optical axis along z (the pole)");
    std::mt19937 rng(14);
    const std::vector<Eigen::Vector3f> points = SimulateRgbd(rng, along_x);
    Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "rgbd", "rgbd.pcd");
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    const std::size_t kept = CheckGrid(*scan, points, 2);
    std::printf("RGB-D-like (%s): %zu of %zu points kept in a %d x %d grid\n", along_x ? "x" : "z", kept, points.size(),
                scan->rows, scan->cols);
    EXPECT_GE(kept, std::size_t(std::ceil(0.99 * points.size())));
    // Looking along x, the columns cover the field of view only (58 deg), not a full turn.
    if (along_x) {
      EXPECT_LT(scan->cols * double(scan->angles.azimuth[1] - scan->angles.azimuth[0]), 60 * kDeg);
    }
  }
}

TEST(OrganizeDefault, PointsWithoutACellAreKeptAsAListAndReportedWithTheirCount) {
  std::mt19937 rng(15);
  std::vector<Eigen::Vector3f> points = SimulateTls(rng, 0.5, 0, 90, -10, 20);
  const std::size_t n = points.size();
  {
    WarningLog log;
    Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "clean", "clean.ply");
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    EXPECT_EQ(scan->CountValid(), n);
    EXPECT_TRUE(log.messages.empty());
  }
  // Five second returns behind first ones (same rays), and every point repeated once more.
  for (int k = 0; k < 5; ++k) points.push_back(points[k] * 1.5f);
  for (std::size_t k = 0; k < n; ++k) points.push_back(points[k]);
  WarningLog log;
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "echoes", "echoes.ply");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->CountValid(), n);
  // Every point is kept: the echoes and the repeats as a list, in the order of the file.
  EXPECT_EQ(scan->CountPoints(), 2 * n + 5);
  ASSERT_EQ(scan->list_points.size(), n + 5);
  EXPECT_EQ(scan->list_reflectance.size(), n + 5);
  std::multiset<Key> in, out;
  for (const Eigen::Vector3f& p : points) in.insert(KeyOf(p));
  scan->ForEachPoint([&](const Eigen::Vector3f& p, float) { out.insert(KeyOf(p)); });
  EXPECT_TRUE(in == out);
  EXPECT_TRUE(scan->single_viewpoint);  // echoes and repeats are no second viewpoint
  ASSERT_EQ(log.messages.size(), 1u);
  const std::string& m = log.messages[0];
  EXPECT_NE(m.find("'echoes.ply'"), std::string::npos) << m;
  EXPECT_NE(m.find(Count(n + 5) + " of " + Count(2 * n + 5)), std::string::npos) << m;
  EXPECT_NE(m.find("5 share a cell with a nearer point"), std::string::npos) << m;
  EXPECT_NE(m.find(Count(n) + " repeat another point exactly"), std::string::npos) << m;
  EXPECT_NE(m.find("kept as a list"), std::string::npos) << m;
}

// A cloud merged from two stations (the second 2 m / 1 m away) organized around the first: the
// points that crowd each other's cells are kept as a list, and the cloud is marked as seen from
// more than one place, with a warning, so no free space is judged from its origin.
TEST(OrganizeDefault, AMergedCloudKeepsEveryPointAndLosesItsViewpoint) {
  std::mt19937 rng(16);
  std::vector<Eigen::Vector3f> points = SimulateTls(rng, 0.5, 0, 360, -30, 40);
  const std::size_t first = points.size();
  for (const Eigen::Vector3f& p : SimulateTls(rng, 0.5, 0, 360, -30, 40)) points.push_back(p + Eigen::Vector3f(2, 1, 0));
  std::shuffle(points.begin(), points.end(), rng);
  WarningLog log;
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "merged", "merged.ply");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  std::printf("merged: %zu of %zu points in the grid (%zu from the first station), %zu as a list\n", scan->CountValid(),
              points.size(), first, scan->list_points.size());
  EXPECT_EQ(scan->CountPoints(), points.size());
  EXPECT_GT(scan->list_points.size(), points.size() / 100);
  EXPECT_FALSE(scan->single_viewpoint);
  ASSERT_EQ(log.warnings, 1);
  EXPECT_NE(log.messages[0].find("not seen from one place"), std::string::npos) << log.messages[0];
  EXPECT_TRUE(scan->Validate().ok());
}

// All points on one ray: one cell holds one of them, the others stay as a list — no point is lost,
// and such a cloud is no view from the origin. A cloud without a usable point is refused.
TEST(OrganizeDefault, ACloudNoGridCanHoldKeepsEveryPointAsAList) {
  std::vector<Eigen::Vector3f> points;
  for (int k = 1; k <= 200; ++k) points.emplace_back(0.1f * k, 0.05f * k, 0.02f * k);
  WarningLog log;
  Expected<Scan> scan = OrganizeCloudByDensity(points, {}, "ray", "ray.pcd");
  ASSERT_TRUE(scan.ok()) << scan.error().ToString();
  EXPECT_EQ(scan->CountPoints(), points.size());
  EXPECT_LT(scan->CountValid(), 10u);
  EXPECT_FALSE(scan->single_viewpoint);
  ASSERT_EQ(log.warnings, 1);
  EXPECT_NE(log.messages[0].find("ray.pcd"), std::string::npos) << log.messages[0];
  Expected<Scan> empty = OrganizeCloudByDensity({Eigen::Vector3f::Zero()}, {}, "z", "z.ply");
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().message.find("z.ply"), std::string::npos) << empty.error().message;
}

// Real clouds: the PCL test cloud (a tilting laser, sensor unstated) and PCL's two 360 deg room
// scans (a rotating line scanner), which hold every point twice. Truth from PCL's own loader.
TEST(OrganizeDefault, RealUnorganizedCloudsKeepNearlyAllTheirPoints) {
  SCANREG_REQUIRE_REALDATA(data);
  for (const char* file :
       {"pcl_test/cturtle.pcd", "pcl_tutorial_data/room_scan1.pcd", "pcl_tutorial_data/room_scan2.pcd"}) {
    SCOPED_TRACE(file);
    pcl::PointCloud<pcl::PointXYZ> cloud;
    ASSERT_EQ(pcl::io::loadPCDFile((data / file).string(), cloud), 0);
    std::vector<Eigen::Vector3f> points;
    std::set<Key> distinct;
    for (const auto& p : cloud) {
      const Eigen::Vector3f q(p.x, p.y, p.z);
      if (!q.allFinite() || q.isZero()) continue;
      points.push_back(q);
      distinct.insert(KeyOf(q));
    }
    NullProgress progress;
    CancelToken cancel;
    WarningLog log;
    Expected<Scan> scan = ReadPcd(data / file, progress, cancel);
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    const std::size_t kept = CheckGrid(*scan, points, 2);
    std::printf("%s: %zu of %zu distinct points (%zu in the file) kept in a %d x %d grid\n", file, kept,
                distinct.size(), points.size(), scan->rows, scan->cols);
    EXPECT_GE(kept, std::size_t(std::ceil(0.99 * distinct.size())));
    EXPECT_EQ(scan->CountPoints(), points.size());  // the repeats too: every point of the file
    if (distinct.size() < points.size()) {
      ASSERT_EQ(log.messages.size(), 1u);
      EXPECT_NE(log.messages[0].find(Count(points.size() - distinct.size()) + " repeat"), std::string::npos)
          << log.messages[0];
    }
  }
}

// A cloud whose points each find a cell (no crowding) but whose file gives sensor positions that lie
// apart was still seen from several places: its origin is no viewpoint. The same points with one
// sensor position for all, or none, keep theirs.
TEST(OrganizeDefault, SensorPositionsThatLieApartSayTheCloudWasSeenFromSeveralPlaces) {
  std::vector<Eigen::Vector3f> points, one_place, two_places;
  for (int r = 0; r < 40; ++r)
    for (int c = 0; c < 160; ++c) {
      const double az = 2 * M_PI * (c + 0.5) / 160, el = (r - 20) * 0.02;
      points.emplace_back(Eigen::Vector3f(5 * std::cos(el) * std::cos(az), 5 * std::cos(el) * std::sin(az), 5 * std::sin(el)));
      one_place.emplace_back(0, 0, 0);
      two_places.emplace_back(c < 80 ? 0.0f : 1.5f, 0, 0);
    }
  const std::vector<float> reflectance(points.size(), 0.5f);
  for (const auto& [sensor, seen_from_one] :
       {std::pair{std::vector<Eigen::Vector3f>{}, true}, std::pair{one_place, true}, std::pair{two_places, false}}) {
    Expected<Scan> scan = OrganizeCloudByDensity(points, reflectance, "c", "c.ply", {}, {}, sensor);
    ASSERT_TRUE(scan.ok()) << scan.error().ToString();
    EXPECT_TRUE(scan->list_points.empty());  // every point has a cell
    EXPECT_EQ(scan->single_viewpoint, seen_from_one) << sensor.size();
    EXPECT_EQ(scan->HasSensor(), !sensor.empty());
  }
}

}  // namespace
}  // namespace scanreg::io
