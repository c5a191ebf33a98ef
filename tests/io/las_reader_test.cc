// LAS input (issue 34, item 4): files written by other programs (libLAS, Global Mapper, TerraScan;
// tests/data/realdata/las_pdal), every point format 0-10 laid out as the specification says (with
// GPS time and RGB), LAS 1.3 waveform data, the longest records, cancellation, and damaged headers.
#include "core/io/las_reader.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/io/las_writer.h"
#include "core/io/scan_file.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

using test::TempDir;

io::LasPoints Read(const std::filesystem::path& path) {
  NullProgress progress;
  Expected<io::LasPoints> las = io::ReadLasPoints(path, progress, CancelToken());
  EXPECT_TRUE(las.ok()) << (las ? "" : las.error().ToString());
  return las ? *las : io::LasPoints{};
}

Error ReadError(const std::filesystem::path& path) {
  NullProgress progress;
  Expected<io::LasPoints> las = io::ReadLasPoints(path, progress, CancelToken());
  EXPECT_FALSE(las.ok()) << path << " was accepted";
  return las ? Error{} : las.error();
}

// A LAS file laid out by the specification (LAS 1.4 R15, tables 3 and 7-17), independently of the
// reader: header, no VLR, then the records, each X Y Z (int32) and intensity (uint16) first and the
// rest of the record filled with a pattern.
struct Synthetic {
  int minor = 2;
  int format = 0;
  int record_length = 0;  // 0: the format's minimum (table lookup below, not the reader's)
  Eigen::Vector3d scale{0.0001, 0.0001, 0.0001};
  Eigen::Vector3d offset{512000.0, 5402000.0, 100.0};
  std::vector<std::array<std::int32_t, 3>> xyz;
  std::vector<std::uint16_t> intensity;
  std::vector<double> gps_time;                      // written where the format has it (table below)
  std::vector<std::array<std::uint16_t, 3>> rgb;     // likewise
  std::uint64_t waveform_start = 0;                  // LAS 1.3+: the header's start of waveform data
  std::uint32_t legacy_count_override = 0xffffffffu;  // else the count written into the legacy field
  std::uint64_t count_override = ~0ull;               // else the count written into the 1.4 field

  std::string Bytes() const {
    static const int kMinimum[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
    const int length = record_length ? record_length : kMinimum[format];
    const int header = minor >= 4 ? 375 : minor == 3 ? 235 : 227;
    std::string b(header, '\0');
    const auto put = [&](std::size_t at, const void* v, std::size_t n) { std::memcpy(&b[at], v, n); };
    std::memcpy(&b[0], "LASF", 4);
    b[24] = 1;
    b[25] = static_cast<char>(minor);
    std::memcpy(&b[58], "scanreg test", 12);
    const std::uint16_t hs = static_cast<std::uint16_t>(header);
    const std::uint32_t offset_to_points = static_cast<std::uint32_t>(header);
    put(94, &hs, 2);
    put(96, &offset_to_points, 4);
    b[104] = static_cast<char>(format);
    const std::uint16_t rl = static_cast<std::uint16_t>(length);
    put(105, &rl, 2);
    const std::uint32_t legacy =
        legacy_count_override != 0xffffffffu ? legacy_count_override : (format <= 5 ? std::uint32_t(xyz.size()) : 0u);
    put(107, &legacy, 4);
    for (int a = 0; a < 3; ++a) {
      put(131 + 8 * a, &scale[a], 8);
      put(155 + 8 * a, &offset[a], 8);
    }
    if (minor >= 3) put(227, &waveform_start, 8);
    if (minor >= 4) {
      const std::uint64_t n = count_override != ~0ull ? count_override : xyz.size();
      put(247, &n, 8);
    }
    // LAS 1.4 R15 tables 7-17: GPS time follows the 20-byte legacy core (formats 1, 3, 4, 5) or the
    // 22-byte core of formats 6-10; RGB follows the core (2), the GPS time (3, 5) or the 30 bytes of
    // format 6 (7, 8, 10).
    static const int kGps[11] = {-1, 20, -1, 20, 20, 20, 22, 22, 22, 22, 22};
    static const int kRgb[11] = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};
    for (std::size_t k = 0; k < xyz.size(); ++k) {
      std::string r(length, '\0');
      for (int i = 0; i < length; ++i) r[i] = static_cast<char>(0xA0 + (i + k) % 37);
      std::memcpy(&r[0], xyz[k].data(), 12);
      std::memcpy(&r[12], &intensity[k], 2);
      if (kGps[format] >= 0 && k < gps_time.size()) std::memcpy(&r[kGps[format]], &gps_time[k], 8);
      if (kRgb[format] >= 0 && k < rgb.size()) std::memcpy(&r[kRgb[format]], rgb[k].data(), 6);
      b += r;
    }
    return b;
  }
  void Write(const std::filesystem::path& path) const {
    std::ofstream(path, std::ios::binary) << Bytes();
  }
};

Synthetic ThreePoints(int minor, int format) {
  Synthetic s;
  s.minor = minor;
  s.format = format;
  s.xyz = {{{0, 0, 0}}, {{123456789, -98765432, 5000}}, {{-2147483647, 2147483647, -1}}};
  s.intensity = {0, 40000, 65535};
  s.gps_time = {0.0, 1234567.891234, 3.0e8 + 0.125};
  s.rgb = {{{0, 0, 0}}, {{65535, 256, 1}}, {{300, 40000, 65535}}};
  return s;
}

TEST(LasReader, ThePermutationFilesOfLibLasGiveThePointPdalExpects) {
  SCANREG_REQUIRE_REALDATA(data);
  for (const char* file : {"1.0_0", "1.0_1", "1.1_0", "1.1_1", "1.2_0", "1.2_1", "1.2_2", "1.2_3"}) {
    SCOPED_TRACE(file);
    const io::LasPoints las = Read(data / "las_pdal" / (std::string(file) + ".las"));
    EXPECT_EQ(las.version_minor, file[2] - '0');
    EXPECT_EQ(las.point_format, file[4] - '0');
    EXPECT_EQ(las.generating_software, "libLAS 1.2");
    ASSERT_EQ(las.xyz.size(), 1u);
    EXPECT_NEAR(las.xyz[0].x(), 470692.44, 1e-9);
    EXPECT_NEAR(las.xyz[0].y(), 4602888.90, 1e-9);
    EXPECT_NEAR(las.xyz[0].z(), 16.00, 1e-9);
    // PDAL's LasReaderTest.test_different_formats expects this GPS time and colour of the point.
    const int format = file[4] - '0';
    ASSERT_EQ(las.gps_time.size(), format == 1 || format == 3 ? 1u : 0u);
    ASSERT_EQ(las.rgb.size(), format >= 2 ? 1u : 0u);
    if (!las.gps_time.empty()) {
      EXPECT_EQ(las.gps_time[0], 1205902800.0);
    }
    if (!las.rgb.empty()) {
      EXPECT_EQ(las.rgb[0], (std::array<std::uint16_t, 3>{255, 12, 234}));
    }
  }
}

// The bounds in the header are the writer's own account of its points: the points we read must
// span exactly them (to half a scale step), far from the origin and at micrometre steps too.
void ExpectHeaderBoundsMatch(const io::LasPoints& las) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const Eigen::Vector3d& p : las.xyz) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(lo[a], las.header_min[a], 0.5 * std::abs(las.scale[a]) + 1e-9) << "axis " << a;
    EXPECT_NEAR(hi[a], las.header_max[a], 0.5 * std::abs(las.scale[a]) + 1e-9) << "axis " << a;
  }
}

TEST(LasReader, AGlobalMapperLas14Format6FarFromTheOriginSpansItsHeaderBounds) {
  SCANREG_REQUIRE_REALDATA(data);
  const io::LasPoints las = Read(data / "las_pdal" / "test1_4.las");
  EXPECT_EQ(las.version_minor, 4);
  EXPECT_EQ(las.point_format, 6);
  EXPECT_EQ(las.generating_software, "Global Mapper");
  ASSERT_EQ(las.xyz.size(), 1000u);
  EXPECT_GT(las.header_min.x(), 1.0e6);  // a real projected coordinate system
  ExpectHeaderBoundsMatch(las);
}

TEST(LasReader, ATerraScanAirborneStripSpansItsHeaderBoundsAndIsKeptWithEveryPoint) {
  SCANREG_REQUIRE_REALDATA(data);
  const std::filesystem::path file = data / "las_pdal" / "simple.las";
  const io::LasPoints las = Read(file);
  EXPECT_EQ(las.point_format, 3);
  ASSERT_EQ(las.xyz.size(), 1065u);
  ExpectHeaderBoundsMatch(las);
  // An airborne strip is seen from no single point: every point is kept (issue 34, item 1), most
  // of them as a list, and the scan is marked as seen from several places.
  NullProgress progress;
  Expected<std::vector<Scan>> scans = io::ReadScanFile(file, progress, CancelToken());
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  ASSERT_EQ(scans->size(), 1u);
  const Scan& strip = scans->front();
  EXPECT_EQ(strip.CountPoints(), las.xyz.size());
  EXPECT_FALSE(strip.single_viewpoint);
  double worst = 0;  // every point where the file puts it (world = pose x local)
  std::vector<Eigen::Vector3d> world;
  strip.ForEachPoint([&](const Eigen::Vector3f& p, float) { world.push_back(strip.world_from_scan * p.cast<double>()); });
  for (const Eigen::Vector3d& q : las.xyz) {
    double best = 1e300;
    for (const Eigen::Vector3d& w : world) best = std::min(best, (w - q).norm());
    worst = std::max(worst, best);
  }
  EXPECT_LT(worst, 1e-3);  // float in a local frame round the median point
}

// A station's scan exported to LAS in UTM coordinates (by our export: the third-party files above
// check the reading) comes back as a scan whose points lie where the file puts them.
TEST(LasReader, AStationInUtmCoordinatesBecomesAScanAtItsWorldPoints) {
  TempDir dir;
  const Scan room = test::MakeRoomScan(60, 120);
  const Eigen::Isometry3d utm = Eigen::Translation3d(512345.678, 5402345.678, 123.4) *
                                Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ());
  io::LasCloud cloud;
  for (std::size_t i = 0; i < room.size(); ++i) {
    if (!room.valid[i]) continue;
    cloud.points.push_back(utm * room.points[i].cast<double>());
    cloud.reflectance.push_back(room.reflectance[i]);
  }
  ASSERT_TRUE(io::WriteLas(dir / "station.las", cloud).ok());
  NullProgress progress;
  Expected<std::vector<Scan>> scans = io::ReadScanFile(dir / "station.las", progress, CancelToken());
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  const Scan& scan = scans->front();
  EXPECT_GE(scan.CountValid(), static_cast<std::size_t>(0.99 * cloud.points.size()));
  // Each kept point is one of the file's points, to the export's 0.1 mm resolution.
  std::vector<Eigen::Vector3d> sorted = cloud.points;
  double worst = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    const Eigen::Vector3d world = scan.world_from_scan * scan.points[i].cast<double>();
    double nearest = INFINITY;
    for (const Eigen::Vector3d& p : sorted) nearest = std::min(nearest, (p - world).norm());
    worst = std::max(worst, nearest);
  }
  EXPECT_LT(worst, 2e-4);
}

TEST(LasReader, EveryPointFormatIsReadExactlyThroughScaleAndOffset) {
  TempDir dir;
  for (int format = 0; format <= 10; ++format) {
    for (int extra : {0, 3}) {
      SCOPED_TRACE("format " + std::to_string(format) + ", extra bytes " + std::to_string(extra));
      Synthetic s = ThreePoints(format <= 5 ? 2 : 4, format);
      s.record_length = io::LasMinimumRecordLength(format) + extra;
      const std::filesystem::path path = dir / ("f" + std::to_string(format) + "_" + std::to_string(extra) + ".las");
      s.Write(path);
      const io::LasPoints las = Read(path);
      ASSERT_EQ(las.xyz.size(), 3u);
      EXPECT_EQ(las.point_format, format);
      for (std::size_t k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) {
          // Double arithmetic, as the specification defines it: exact to the last bits.
          const double expected = s.xyz[k][a] * s.scale[a] + s.offset[a];
          EXPECT_NEAR(las.xyz[k][a], expected, 0.01 * s.scale[a]);  // far below one raw unit
        }
        EXPECT_EQ(las.intensity[k], s.intensity[k]);
      }
      const bool gps = format == 1 || format >= 3, rgb = format == 2 || format == 3 || format == 5 || format == 7 ||
                                                           format == 8 || format == 10;
      ASSERT_EQ(las.gps_time.size(), gps ? 3u : 0u);
      ASSERT_EQ(las.rgb.size(), rgb ? 3u : 0u);
      for (std::size_t k = 0; k < las.gps_time.size(); ++k) EXPECT_EQ(las.gps_time[k], s.gps_time[k]);
      for (std::size_t k = 0; k < las.rgb.size(); ++k) EXPECT_EQ(las.rgb[k], s.rgb[k]);
    }
  }
  EXPECT_EQ(io::LasMinimumRecordLength(11), 0);
}

// A scan keeps each point's GPS time with the base the header's global encoding gives (bit 0: adjusted
// standard GPS time, else GPS week seconds).
TEST(LasReader, AScanKeepsEachPointsTimeAndItsBase) {
  TempDir dir;
  for (bool adjusted : {false, true}) {
    SCOPED_TRACE(adjusted ? "adjusted standard GPS time" : "GPS week seconds");
    Synthetic s;
    s.format = 1;
    for (int k = 0; k < 200; ++k) {  // a ring of points 10 m around, each with its own time
      const double a = 2 * M_PI * k / 200.0;
      s.xyz.push_back({{int(1e5 * std::cos(a)), int(1e5 * std::sin(a)), 1000 * (k % 7)}});
      s.intensity.push_back(static_cast<std::uint16_t>(k));
      s.gps_time.push_back((adjusted ? 3.0e8 : 2.0e5) + 0.001 * k);
    }
    std::string b = s.Bytes();
    b[6] = adjusted ? 1 : 0;
    std::ofstream(dir / "t.las", std::ios::binary) << b;
    NullProgress progress;
    Expected<std::vector<Scan>> scans = io::ReadScanFile(dir / "t.las", progress, CancelToken());
    ASSERT_TRUE(scans.ok()) << scans.error().ToString();
    const Scan& scan = scans->front();
    ASSERT_TRUE(scan.HasTime());
    EXPECT_EQ(scan.time_base, adjusted ? io::kAdjustedGpsTime : io::kGpsWeekSeconds);
    std::size_t right = 0;
    const auto check = [&](const Eigen::Vector3f& local, double t) {
      const Eigen::Vector3d p = scan.world_from_scan * local.cast<double>();
      for (std::size_t k = 0; k < s.xyz.size(); ++k) {
        const Eigen::Vector3d q(s.xyz[k][0] * s.scale[0] + s.offset[0], s.xyz[k][1] * s.scale[1] + s.offset[1],
                                s.xyz[k][2] * s.scale[2] + s.offset[2]);
        if ((p - q).norm() < 1e-3) right += t == s.gps_time[k];
      }
    };
    for (std::size_t i = 0; i < scan.size(); ++i)
      if (scan.valid[i]) check(scan.points[i], scan.time[i]);
    for (std::size_t k = 0; k < scan.list_points.size(); ++k) check(scan.list_points[k], scan.list_time[k]);
    EXPECT_EQ(right, s.xyz.size());
  }
}

// LAS 1.3 (a 235-byte header with the start of internal waveform data, formats 4 and 5 carrying
// waveform packets): the points end where the waveform data begin.
TEST(LasReader, ALas13FileWithInternalWaveformDataEndsItsPointsThere) {
  TempDir dir;
  for (int format : {1, 4, 5}) {
    SCOPED_TRACE("format " + std::to_string(format));
    Synthetic s = ThreePoints(3, format);
    std::string b = s.Bytes();
    const std::uint64_t waveform = b.size();
    std::memcpy(&b[227], &waveform, 8);
    b += std::string(3 * io::LasMinimumRecordLength(format), '\x33');  // waveform bytes, three records long
    std::ofstream(dir / "w.las", std::ios::binary) << b;
    const io::LasPoints las = Read(dir / "w.las");
    EXPECT_EQ(las.version_minor, 3);
    ASSERT_EQ(las.xyz.size(), 3u);
    EXPECT_NEAR(las.xyz[2].z(), s.xyz[2][2] * s.scale.z() + s.offset.z(), 0.01 * s.scale.z());
    EXPECT_EQ(las.gps_time[1], s.gps_time[1]);
    // A header promising 5 points finds only 3 before the waveform data.
    const std::uint32_t five = 5;
    std::memcpy(&b[107], &five, 4);
    std::ofstream(dir / "w5.las", std::ios::binary) << b;
    EXPECT_NE(ReadError(dir / "w5.las").message.find("holds only 3 complete"), std::string::npos);
  }
}

// The longest record the header can describe (65,535 bytes: a format's fields and extra bytes) is
// read in chunks, every point exact; a cancelled read returns at once, naming the file.
TEST(LasReader, RecordsOf64KilobytesAreReadAndACancelledReadStops) {
  TempDir dir;
  Synthetic s = ThreePoints(4, 7);
  s.record_length = 65535;
  for (int k = 0; k < 400; ++k) {  // 26 MB: more than one 16 MB chunk
    s.xyz.push_back({{k * 1000, -k * 7, k}});
    s.intensity.push_back(static_cast<std::uint16_t>(k));
    s.gps_time.push_back(k + 0.5);
    s.rgb.push_back({{static_cast<std::uint16_t>(k), 7, 65535}});
  }
  s.Write(dir / "long.las");
  const io::LasPoints las = Read(dir / "long.las");
  ASSERT_EQ(las.xyz.size(), s.xyz.size());
  EXPECT_EQ(las.record_length, 65535);
  for (std::size_t k = 0; k < s.xyz.size(); ++k) {
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(las.xyz[k][a], s.xyz[k][a] * s.scale[a] + s.offset[a], 0.01 * s.scale[a]);
    EXPECT_EQ(las.intensity[k], s.intensity[k]);
    EXPECT_EQ(las.gps_time[k], s.gps_time[k]);
    EXPECT_EQ(las.rgb[k], s.rgb[k]);
  }
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  Expected<io::LasPoints> cancelled = io::ReadLasPoints(dir / "long.las", progress, cancel);
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.error().code, ErrorCode::kCancelled);
  EXPECT_NE(cancelled.error().message.find("long.las"), std::string::npos);
}

// LASzip marks compressed points in the format byte (tested with the damaged files below); an
// uncompressed file that only carries the .laz name is read as what it is.
TEST(LasReader, AnUncompressedFileNamedLazIsRead) {
  TempDir dir;
  const Synthetic s = ThreePoints(2, 3);
  s.Write(dir / "points.laz");
  const io::LasPoints las = Read(dir / "points.laz");
  ASSERT_EQ(las.xyz.size(), 3u);
  EXPECT_EQ(las.rgb[2], s.rgb[2]);
}

// Points start at the header's offset (after VLRs), the 64-bit count wins over the legacy one in
// LAS 1.4, and extended VLRs after the points are not read as points.
TEST(LasReader, PointsStartAtTheirOffsetAndEndBeforeExtendedVlrs) {
  TempDir dir;
  Synthetic s = ThreePoints(4, 1);
  std::string b = s.Bytes();
  const std::string vlr(54 + 16, '\x5a');  // a VLR-sized gap between header and points
  b.insert(375, vlr);
  const std::uint32_t offset = 375 + static_cast<std::uint32_t>(vlr.size());
  std::memcpy(&b[96], &offset, 4);
  const std::uint32_t legacy = 2;  // disagrees with the 64-bit count (3): the 64-bit one wins
  std::memcpy(&b[107], &legacy, 4);
  const std::uint64_t evlr = b.size();
  std::memcpy(&b[235], &evlr, 8);
  b += std::string(2 * 28, '\x11');  // an extended VLR's bytes, as long as two records
  std::ofstream(dir / "vlr.las", std::ios::binary) << b;
  const io::LasPoints las = Read(dir / "vlr.las");
  ASSERT_EQ(las.xyz.size(), 3u);
  EXPECT_NEAR(las.xyz[1].x(), s.xyz[1][0] * s.scale.x() + s.offset.x(), 0.01 * s.scale.x());
  // A header promising 5 points finds only 3 before the extended VLR.
  const std::uint64_t five = 5;
  std::memcpy(&b[247], &five, 8);
  std::ofstream(dir / "over.las", std::ios::binary) << b;
  EXPECT_NE(ReadError(dir / "over.las").message.find("holds only 3 complete"), std::string::npos);
}

TEST(LasReader, ALas14FileWithOnlyTheLegacyCountIsReadToo) {
  TempDir dir;
  Synthetic s = ThreePoints(4, 1);
  s.count_override = 0;  // the 64-bit count left at zero by a writer that fills only the legacy one
  s.Write(dir / "legacy.las");
  EXPECT_EQ(Read(dir / "legacy.las").xyz.size(), 3u);
}

TEST(LasReader, DamagedFilesAreClearErrorsNamingTheFileAndWhatToDo) {
  TempDir dir;
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return dir / name;
  };
  const std::string good = ThreePoints(4, 6).Bytes();
  struct Case {
    std::string name, bytes, expect;
  };
  std::vector<Case> cases;
  cases.push_back({"short.las", good.substr(0, 100), "shorter than a LAS header"});
  std::string sig = good;
  sig[0] = 'X';
  cases.push_back({"signature.las", sig, "not a LAS file"});
  cases.push_back({"truncated.las", good.substr(0, good.size() - 10), "holds only 2 complete"});
  std::string version = good;
  version[25] = 7;
  cases.push_back({"version.las", version, "LAS version 1.7"});
  std::string format = good;
  format[104] = 11;
  cases.push_back({"format.las", format, "record format 11"});
  std::string laz = good;
  laz[104] = static_cast<char>(6 | 0x80);
  cases.push_back({"compressed.las", laz, "decompress"});
  std::string laz6 = good;
  laz6[104] = static_cast<char>(6 | 0x40);
  cases.push_back({"compressed6.las", laz6, "decompress"});
  std::string length = good;
  length[105] = 20;
  length[106] = 0;
  cases.push_back({"length.las", length, "needs at least 30"});
  std::string scale = good;
  std::memset(&scale[131], 0, 8);
  cases.push_back({"scale.las", scale, "scale factor"});
  std::string overflow = good;
  const double huge_scale = 1e308;
  std::memcpy(&overflow[131], &huge_scale, 8);
  cases.push_back({"overflow.las", overflow, "not a finite number"});
  std::string header = good;
  header[94] = static_cast<char>(200);
  header[95] = 0;
  cases.push_back({"header.las", header, "at least 375"});
  std::string offset = good;
  offset[96] = 10;
  offset[97] = offset[98] = offset[99] = 0;
  cases.push_back({"offset.las", offset, "inside the"});
  Synthetic huge = ThreePoints(4, 6);
  huge.count_override = 1ull << 40;  // a trillion points promised by a 500-byte file: no allocation
  cases.push_back({"huge.las", huge.Bytes(), "promises 1099511627776 points"});
  std::string zero = ThreePoints(2, 1).Bytes();  // LAS 1.2: the legacy count is the only one
  std::memset(&zero[107], 0, 4);
  cases.push_back({"zero.las", zero, "says it holds 0 points, but 3 complete"});
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const Error e = ReadError(write(c.name, c.bytes));
    EXPECT_NE(e.message.find(c.name), std::string::npos) << e.message;
    EXPECT_NE(e.message.find(c.expect), std::string::npos) << e.message;
  }
  NullProgress progress;
  Expected<std::vector<Scan>> via_dispatch = io::ReadScanFile(dir / "truncated.las", progress, CancelToken());
  ASSERT_FALSE(via_dispatch.ok());
  EXPECT_NE(via_dispatch.error().message.find("truncated"), std::string::npos);
}

TEST(LasReader, ScanFilesRefuseToWriteLasAndPointToTheExport) {
  TempDir dir;
  NullProgress progress;
  const Status s = io::WriteScanFile(dir / "out.las", {Scan("a", 1, 1)}, progress, CancelToken());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("export-clouds"), std::string::npos) << s.error().message;
}

}  // namespace
}  // namespace scanreg
