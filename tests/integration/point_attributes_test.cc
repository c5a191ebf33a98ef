// Per-point attributes other programs write and read (issue 34): each point's GPS time and its
// sensor position, from import to export, read back by readers that are not ours (PCL, LAS and E57
// decoded by their specifications).
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/io/ply_io.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <random>

#include "core/pipeline/export_clouds.h"
#include "tests/integration/import_file.h"
#include "tests/io/e57_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

// A mobile mapper's cloud with each point's sensor position (PLY x_origin y_origin z_origin, as
// the Paris-rue-Madame and iQmulus sets write it; issue 34): every point keeps its own on import,
// and the exported PLY gives it back to PCL's reader, in world coordinates beside the point.
TEST(ThirdPartyReaders, EveryPointKeepsItsSensorPositionFromImportToExport) {
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> stations = TwoStreetStations();
  ASSERT_TRUE(stations.ok()) << stations.error().ToString();
  // Point -> its station, keyed by the point as written (5 decimals).
  std::map<std::array<long long, 3>, Eigen::Vector3d> origin_of;
  auto key = [](const Eigen::Vector3d& p) {
    return std::array<long long, 3>{std::llround(p.x() * 1e4), std::llround(p.y() * 1e4), std::llround(p.z() * 1e4)};
  };
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> merged;  // (point, sensor)
  for (const Scan& s : *stations)
    for (std::size_t k = 0; k < s.size(); ++k)
      if (s.valid[k])
        merged.push_back({*s.reference_world_from_scan * s.points[k].cast<double>(),
                          s.reference_world_from_scan->translation() + Eigen::Vector3d(0.01 * (k % 7), 0.0, 0.0)});
  std::shuffle(merged.begin(), merged.end(), std::mt19937(4));
  const std::filesystem::path file = dir / "mobile.ply";
  {
    std::FILE* f = std::fopen(file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fprintf(f, "ply\nformat ascii 1.0\nelement vertex %zu\nproperty float x\nproperty float y\n"
                 "property float z\nproperty float x_origin\nproperty float y_origin\nproperty float z_origin\n"
                 "property float reflectance\nend_header\n", merged.size());
    for (auto& [p, s] : merged) {
      std::fprintf(f, "%.4f %.4f %.4f %.4f %.4f %.4f 0.5\n", p.x(), p.y(), p.z(), s.x(), s.y(), s.z());
      p = Eigen::Vector3d(std::round(p.x() * 1e4), std::round(p.y() * 1e4), std::round(p.z() * 1e4)) * 1e-4;
      s = Eigen::Vector3d(std::round(s.x() * 1e4), std::round(s.y() * 1e4), std::round(s.z() * 1e4)) * 1e-4;
      origin_of[key(p)] = s;
    }
    std::fclose(f);
  }
  std::optional<Imported> in = ImportFile(file, dir.path());
  ASSERT_TRUE(in);
  const Scan& scan = in->scans.front();
  ASSERT_TRUE(scan.HasSensor());
  EXPECT_FALSE(scan.single_viewpoint);
  ASSERT_EQ(scan.CountPoints(), merged.size());
  // The float of the file is kept as a float: a few tenths of a millimetre at 6 m.
  auto wrong = [&](const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& read) {
    std::size_t bad = 0;
    for (const auto& [p, s] : read) {
      auto it = origin_of.find(key(p));
      bad += it == origin_of.end() || (it->second - s).norm() > 1e-3;
    }
    return bad;
  };
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> imported;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i])
      imported.push_back({scan.world_from_scan * scan.points[i].cast<double>(), scan.world_from_scan * scan.sensor[i].cast<double>()});
  for (std::size_t k = 0; k < scan.list_points.size(); ++k)
    imported.push_back({scan.world_from_scan * scan.list_points[k].cast<double>(),
                        scan.world_from_scan * scan.list_sensor[k].cast<double>()});
  ASSERT_EQ(imported.size(), merged.size());
  EXPECT_EQ(wrong(imported), 0u);

  in->project.scans[0].registered = true;
  pipeline::ExportCloudsOptions options;
  options.dir = dir / "ply";
  options.format = "ply";
  auto exported = pipeline::ExportClouds(in->project, options, progress, cancel);
  ASSERT_TRUE(exported.ok()) << exported.error().ToString();
  pcl::PCLPointCloud2 cloud;
  ASSERT_EQ(pcl::io::loadPLYFile((*exported)[0].file.string(), cloud), 0);
  int offset[6] = {-1, -1, -1, -1, -1, -1};
  const char* names[6] = {"x", "y", "z", "scalar_x_origin", "scalar_y_origin", "scalar_z_origin"};
  for (const auto& f : cloud.fields)
    for (int d = 0; d < 6; ++d)
      if (f.name == names[d] && f.datatype == pcl::PCLPointField::FLOAT64) offset[d] = static_cast<int>(f.offset);
  for (int d = 0; d < 6; ++d) ASSERT_GE(offset[d], 0) << "PCL found no double " << names[d];
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> read;
  for (std::size_t i = 0; i < std::size_t(cloud.width) * cloud.height; ++i) {
    double v[6];
    for (int d = 0; d < 6; ++d) std::memcpy(&v[d], cloud.data.data() + i * cloud.point_step + offset[d], 8);
    read.push_back({Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5])});
  }
  ASSERT_EQ(read.size(), merged.size());
  EXPECT_EQ(wrong(read), 0u);
}

// Each record's position and GPS time of a LAS file, decoded here from the specification (LAS 1.4
// R15, tables 3 and 7-17: the legacy count at 107 before 1.4, the 64-bit one at 247 from 1.4; GPS
// time at byte 20 of formats 1 and 3-5, 22 of formats 6-10), not by scanreg's reader; and the
// global encoding's bit 0 (adjusted standard GPS time).
struct TimedLas {
  std::vector<Eigen::Vector3d> xyz;
  std::vector<double> time;
  bool adjusted = false;
};
TimedLas ReadTimesBySpecification(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  TimedLas out;
  if (b.size() < 227 || b.compare(0, 4, "LASF") != 0) return out;
  auto get = [&](std::size_t at, auto value) {
    std::memcpy(&value, b.data() + at, sizeof value);
    return value;
  };
  out.adjusted = (get(6, std::uint16_t{}) & 1u) != 0;
  const int minor = b[25], format = static_cast<unsigned char>(b[104]) & 0x3f;
  const std::uint32_t first = get(96, std::uint32_t{});
  const std::uint16_t length = get(105, std::uint16_t{});
  const std::uint64_t count = minor >= 4 ? get(247, std::uint64_t{}) : get(107, std::uint32_t{});
  const int gps_at = format >= 6 ? 22 : (format == 1 || format >= 3) ? 20 : -1;
  if (gps_at < 0 || first + count * length > b.size()) return out;
  double scale[3], offset[3];
  for (int d = 0; d < 3; ++d) scale[d] = get(131 + 8 * d, double{}), offset[d] = get(155 + 8 * d, double{});
  for (std::uint64_t k = 0; k < count; ++k) {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) p[d] = offset[d] + scale[d] * get(first + k * length + 4 * d, std::int32_t{});
    out.xyz.push_back(p);
    out.time.push_back(get(first + k * length + gps_at, double{}));
  }
  return out;
}

// For every point of `read`, the time of the nearest point of `truth` (within 1 mm) differs from
// its own: how many do (a point with no truth point that near counts too).
std::size_t WrongTimes(const std::vector<std::pair<Eigen::Vector3d, double>>& read, const TimedLas& truth) {
  std::size_t wrong = 0;
  for (const auto& [p, t] : read) {
    std::size_t best = truth.xyz.size();
    double best_d = 1e-3;
    for (std::size_t k = 0; k < truth.xyz.size(); ++k) {
      const double d = (truth.xyz[k] - p).norm();
      if (d < best_d) best_d = d, best = k;
    }
    wrong += best == truth.xyz.size() || truth.time[best] != t;
  }
  return wrong;
}

// Issue 34 item 1: a point keeps its time. An airborne strip written by TerraScan (PDAL's
// simple.las: LAS 1.2, format 3, a GPS time per point) is imported with every point's own time and
// exported with it (E57: decoded by the standard, timeStamps without a date, as week seconds have none):
// PCL reads the PLY's scalar_GpsTime property (CloudCompare's name), the LAS's records decoded by the
// specification hold them with the file's time base (global encoding bit 0), each at its point.
TEST(ThirdPartyReaders, EveryPointKeepsItsGpsTimeFromImportToExport) {
  SCANREG_REQUIRE_REALDATA(data);
  test::TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::filesystem::path file = data / "las_pdal" / "simple.las";
  const TimedLas truth = ReadTimesBySpecification(file);
  ASSERT_EQ(truth.xyz.size(), 1065u);
  ASSERT_GT(*std::max_element(truth.time.begin(), truth.time.end()),
            *std::min_element(truth.time.begin(), truth.time.end()));  // the times differ: a point's own counts
  std::optional<Imported> in = ImportFile(file, dir.path());
  ASSERT_TRUE(in);
  const Scan& scan = in->scans.front();
  ASSERT_TRUE(scan.HasTime());
  EXPECT_EQ(scan.time_base, truth.adjusted ? "adjusted standard GPS time (GPS seconds - 1e9)" : "GPS week seconds");
  std::vector<std::pair<Eigen::Vector3d, double>> imported;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) imported.push_back({scan.world_from_scan * scan.points[i].cast<double>(), scan.time[i]});
  for (std::size_t k = 0; k < scan.list_points.size(); ++k)
    imported.push_back({scan.world_from_scan * scan.list_points[k].cast<double>(), scan.list_time[k]});
  ASSERT_EQ(imported.size(), truth.xyz.size());
  EXPECT_EQ(WrongTimes(imported, truth), 0u);

  in->project.scans[0].registered = true;
  for (const char* format : {"ply", "las", "e57"}) {
    SCOPED_TRACE(format);
    pipeline::ExportCloudsOptions options;
    options.dir = dir / format;
    options.format = format;
    auto exported = pipeline::ExportClouds(in->project, options, progress, cancel);
    ASSERT_TRUE(exported.ok()) << exported.error().ToString();
    const std::filesystem::path out = (*exported)[0].file;
    std::vector<std::pair<Eigen::Vector3d, double>> read;
    if (std::string(format) == "ply") {
      pcl::PCLPointCloud2 cloud;
      ASSERT_EQ(pcl::io::loadPLYFile(out.string(), cloud), 0);
      int xyz[3] = {-1, -1, -1}, time = -1;
      for (const auto& f : cloud.fields) {
        for (int d = 0; d < 3; ++d)
          if (f.name == std::string(1, char('x' + d))) xyz[d] = f.offset;
        if (f.name == "scalar_GpsTime" && f.datatype == pcl::PCLPointField::FLOAT64) time = f.offset;
      }
      ASSERT_GE(time, 0) << "PCL found no scalar_GpsTime (double) property";
      for (std::size_t i = 0; i < std::size_t(cloud.width) * cloud.height; ++i) {
        Eigen::Vector3d p;
        double t = 0;
        for (int d = 0; d < 3; ++d) std::memcpy(&p[d], cloud.data.data() + i * cloud.point_step + xyz[d], 8);
        std::memcpy(&t, cloud.data.data() + i * cloud.point_step + time, 8);
        read.push_back({p, t});
      }
    } else if (std::string(format) == "e57") {  // decoded by the standard: GPS week seconds name no date,
      std::ifstream in(out, std::ios::binary);  // so the timeStamps are the times themselves
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const test::E57BySpecification e57 = test::DecodeE57BySpecification(bytes);
      EXPECT_EQ(e57.acquisition_start.has_value(), truth.adjusted);
      const std::vector<double>& t = e57.Field("timeStamp");
      ASSERT_EQ(t.size(), e57.records);
      for (std::size_t r = 0; r < e57.records; ++r)
        read.push_back({e57.World(r), truth.adjusted ? *e57.acquisition_start - 1e9 + t[r] : t[r]});
    } else {
      const TimedLas las = ReadTimesBySpecification(out);
      EXPECT_EQ(las.adjusted, truth.adjusted);
      for (std::size_t k = 0; k < las.xyz.size(); ++k) read.push_back({las.xyz[k], las.time[k]});
    }
    ASSERT_EQ(read.size(), truth.xyz.size());
    EXPECT_EQ(WrongTimes(read, truth), 0u);
  }
}

}  // namespace
}  // namespace scanreg
