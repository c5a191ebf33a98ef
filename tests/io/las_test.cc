// LAS 1.4 writer: the bytes are checked against the ASPRS LAS 1.4 R15 layout (public header block,
// VLR header, point data record formats 6 and 7) by offsets taken from the specification, not by a
// reader of ours.
#include "core/io/las_writer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <random>

#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::ReadBytes;
using test::TempDir;

// Public header block offsets (LAS 1.4 R15, table "Public Header Block").
constexpr std::size_t kGlobalEncoding = 6, kVersionMajor = 24, kVersionMinor = 25, kSystemId = 26, kSoftware = 58,
                      kDay = 90, kYear = 92, kHeaderSize = 94, kOffsetToPoints = 96, kNumVlrs = 100, kFormat = 104,
                      kRecordLength = 105, kLegacyCount = 107, kLegacyByReturn = 111, kScale = 131, kOffset = 155,
                      kMaxX = 179, kWaveform = 227, kFirstEvlr = 235, kNumEvlrs = 243, kPointCount = 247,
                      kByReturn = 255;

// Reads little-endian fields (the test hosts are little-endian, like every supported platform).
struct Bytes {
  std::string data;

  template <typename T>
  T At(std::size_t offset) const {
    T v{};
    if (offset + sizeof(T) > data.size()) {
      ADD_FAILURE() << "read of " << sizeof(T) << " bytes at " << offset << " past the end (" << data.size() << ")";
      return v;
    }
    std::memcpy(&v, data.data() + offset, sizeof(T));
    return v;
  }
  std::string Text(std::size_t offset, std::size_t width) const {
    return offset + width <= data.size() ? data.substr(offset, width) : std::string();
  }
};

std::string Padded(const std::string& text, std::size_t width) { return text + std::string(width - text.size(), '\0'); }

std::vector<std::string> Listing(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// A 50 m box about 500 km east and 5,000 km north of the origin: 0.1 mm needs the offset.
LasCloud GeoreferencedCloud(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> box(0.0, 50.0);
  std::uniform_real_distribution<float> refl(-0.2f, 1.2f);  // outside [0,1] too: clamped
  LasCloud cloud;
  const Eigen::Vector3d base(500000.37, 5000000.81, 100.2);
  for (std::size_t i = 0; i < n; ++i) {
    cloud.points.push_back(base + Eigen::Vector3d(box(rng), box(rng), box(rng)));
    cloud.reflectance.push_back(refl(rng));
    cloud.source_ids.push_back(static_cast<std::uint16_t>(i % 3));
  }
  cloud.source_names = {"station A", "station B", "roof"};
  return cloud;
}

std::uint16_t ExpectedIntensity(float r) {
  if (std::isnan(r)) return 0;
  return static_cast<std::uint16_t>(std::lround(std::min(1.0, std::max(0.0, double(r))) * 65535.0));
}

std::pair<int, int> UtcDayAndYear() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  return {utc.tm_yday + 1, utc.tm_year + 1900};
}

TEST(LasWriter, Format6HeaderVlrAndPointsFollowTheSpec) {
  TempDir dir;
  LasCloud cloud = GeoreferencedCloud(5000, 7);
  cloud.reflectance[5] = std::numeric_limits<float>::quiet_NaN();
  cloud.reflectance[6] = 0.0f;
  cloud.reflectance[7] = 1.0f;
  const auto before = UtcDayAndYear();
  const Status status = WriteLas(dir / "cloud.las", cloud);
  const auto after = UtcDayAndYear();
  ASSERT_TRUE(status.ok()) << status.error().ToString();
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"cloud.las"});
  const Bytes las{ReadBytes(dir / "cloud.las")};
  ASSERT_GE(las.data.size(), 375u + 54u);

  EXPECT_EQ(las.Text(0, 4), "LASF");
  EXPECT_EQ(las.At<std::uint16_t>(4), 0);                     // file source ID
  EXPECT_EQ(las.At<std::uint16_t>(kGlobalEncoding), 1 << 4);  // WKT bit only
  EXPECT_EQ(las.Text(8, 16), std::string(16, '\0'));          // GUID
  EXPECT_EQ(las.At<std::uint8_t>(kVersionMajor), 1);
  EXPECT_EQ(las.At<std::uint8_t>(kVersionMinor), 4);
  EXPECT_EQ(las.Text(kSystemId, 32), Padded("scanreg export", 32));
  EXPECT_EQ(las.Text(kSoftware, 32), Padded("scanreg", 32));
  const std::pair<int, int> written{las.At<std::uint16_t>(kDay), las.At<std::uint16_t>(kYear)};
  EXPECT_TRUE(written == before || written == after) << written.first << "/" << written.second;
  EXPECT_EQ(las.At<std::uint16_t>(kHeaderSize), 375);
  EXPECT_EQ(las.At<std::uint32_t>(kNumVlrs), 1u);
  EXPECT_EQ(las.At<std::uint8_t>(kFormat), 6);
  EXPECT_EQ(las.At<std::uint16_t>(kRecordLength), 30);
  EXPECT_EQ(las.At<std::uint32_t>(kLegacyCount), 0u);  // must be 0 for formats 6-10
  for (int r = 0; r < 5; ++r) EXPECT_EQ(las.At<std::uint32_t>(kLegacyByReturn + 4 * r), 0u) << r;
  EXPECT_EQ(las.At<std::uint64_t>(kWaveform), 0u);
  EXPECT_EQ(las.At<std::uint64_t>(kFirstEvlr), 0u);
  EXPECT_EQ(las.At<std::uint32_t>(kNumEvlrs), 0u);
  const std::size_t n = cloud.points.size();
  EXPECT_EQ(las.At<std::uint64_t>(kPointCount), n);
  EXPECT_EQ(las.At<std::uint64_t>(kByReturn), n);  // all points are return 1 of 1
  for (int r = 1; r < 15; ++r) EXPECT_EQ(las.At<std::uint64_t>(kByReturn + 8 * r), 0u) << r;

  // Scale, offset (bounding box minimum rounded down to a metre).
  Eigen::Vector3d lo = cloud.points[0], hi = cloud.points[0];
  for (const auto& p : cloud.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  Eigen::Vector3d scale, offset;
  for (int a = 0; a < 3; ++a) {
    scale[a] = las.At<double>(kScale + 8 * a);
    offset[a] = las.At<double>(kOffset + 8 * a);
    EXPECT_EQ(scale[a], 0.0001) << a;
    EXPECT_EQ(offset[a], std::floor(lo[a])) << a;
  }

  // The VLR: 54-byte header, then "id<TAB>name\n" lines.
  const std::string names = "0\tstation A\n1\tstation B\n2\troof\n";
  EXPECT_EQ(las.At<std::uint16_t>(375), 0);  // reserved
  EXPECT_EQ(las.Text(377, 16), Padded("scanreg", 16));
  EXPECT_EQ(las.At<std::uint16_t>(393), 1);  // record ID
  EXPECT_EQ(las.At<std::uint16_t>(395), names.size());
  EXPECT_EQ(las.Text(397, 32), Padded("scan names by point source ID", 32));
  EXPECT_EQ(las.Text(375 + 54, names.size()), names);
  const std::uint32_t first = las.At<std::uint32_t>(kOffsetToPoints);
  EXPECT_EQ(first, 375u + 54u + names.size());
  ASSERT_EQ(las.data.size(), first + n * 30);

  // Points: decode X * scale + offset; each within 0.1 mm (quantization alone is <= 0.05 mm).
  Eigen::Vector3d decoded_lo = Eigen::Vector3d::Constant(1e300), decoded_hi = -decoded_lo;
  double worst = 0.0;
  std::size_t bad_fields = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t at = first + i * 30;
    Eigen::Vector3d p;
    for (int a = 0; a < 3; ++a) p[a] = las.At<std::int32_t>(at + 4 * a) * scale[a] + offset[a];
    worst = std::max(worst, (p - cloud.points[i]).cwiseAbs().maxCoeff());
    decoded_lo = decoded_lo.cwiseMin(p), decoded_hi = decoded_hi.cwiseMax(p);
    bad_fields += las.At<std::uint16_t>(at + 12) != ExpectedIntensity(cloud.reflectance[i]);
    bad_fields += las.At<std::uint8_t>(at + 14) != 0x11;  // return number 1 (bits 0-3), of 1 return (bits 4-7)
    bad_fields += las.At<std::uint8_t>(at + 15) != 0;     // flags, scanner channel, scan direction, edge
    bad_fields += las.At<std::uint8_t>(at + 16) != 0;     // classification
    bad_fields += las.At<std::uint8_t>(at + 17) != 0;     // user data
    bad_fields += las.At<std::int16_t>(at + 18) != 0;     // scan angle
    bad_fields += las.At<std::uint16_t>(at + 20) != cloud.source_ids[i];
    bad_fields += las.At<double>(at + 22) != 0.0;  // GPS time
  }
  EXPECT_LE(worst, 0.0001);
  EXPECT_EQ(bad_fields, 0u);
  EXPECT_EQ(las.At<std::uint16_t>(first + 5 * 30 + 12), 0);      // NaN reflectance
  EXPECT_EQ(las.At<std::uint16_t>(first + 6 * 30 + 12), 0);      // 0
  EXPECT_EQ(las.At<std::uint16_t>(first + 7 * 30 + 12), 65535);  // 1
  EXPECT_EQ(las.At<std::uint16_t>(first + 20 + 30 * 4), 1);      // point 4 is from scan 1

  // Header bounds are those of the quantized points, and close to the input's.
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(las.At<double>(kMaxX + 16 * a), decoded_hi[a], 1e-9) << a;
    EXPECT_NEAR(las.At<double>(kMaxX + 16 * a + 8), decoded_lo[a], 1e-9) << a;
    EXPECT_NEAR(decoded_hi[a], hi[a], 0.0001) << a;
    EXPECT_NEAR(decoded_lo[a], lo[a], 0.0001) << a;
  }
}

TEST(LasWriter, ColourSelectsFormat7With16BitChannels) {
  TempDir dir;
  LasCloud cloud;
  cloud.points = {{-12.25, 3.5, -0.75}, {-11.0, 4.0001, 0.0}, {10.1234, -7.0, 2.5}};
  cloud.rgb = {{{0, 128, 255}}, {{1, 2, 3}}, {{255, 255, 255}}};
  ASSERT_TRUE(WriteLas(dir / "rgb.las", cloud).ok());
  const Bytes las{ReadBytes(dir / "rgb.las")};
  ASSERT_GE(las.data.size(), 375u);
  EXPECT_EQ(las.At<std::uint8_t>(kFormat), 7);
  EXPECT_EQ(las.At<std::uint16_t>(kRecordLength), 36);
  EXPECT_EQ(las.At<std::uint16_t>(395), 0);  // no names: empty VLR payload
  const std::uint32_t first = las.At<std::uint32_t>(kOffsetToPoints);
  EXPECT_EQ(first, 375u + 54u);
  ASSERT_EQ(las.data.size(), first + 3 * 36);
  EXPECT_EQ(las.At<double>(kOffset), -13.0);  // floor of negative minima
  EXPECT_EQ(las.At<double>(kOffset + 16), -1.0);
  for (std::size_t i = 0; i < 3; ++i) {
    const std::size_t at = first + i * 36;
    for (int a = 0; a < 3; ++a) {
      const double v = las.At<std::int32_t>(at + 4 * a) * 0.0001 + las.At<double>(kOffset + 8 * a);
      EXPECT_NEAR(v, cloud.points[i][a], 0.00005) << i << " " << a;
    }
    EXPECT_EQ(las.At<std::uint16_t>(at + 12), 0) << i;  // no reflectance: intensity 0
    EXPECT_EQ(las.At<std::uint16_t>(at + 20), 0) << i;  // no source IDs: 0
    for (int c = 0; c < 3; ++c) EXPECT_EQ(las.At<std::uint16_t>(at + 30 + 2 * c), cloud.rgb[i][c] * 256) << i;
  }
}

// Per-point times (LAS 1.4 R15 table 13: GPS time, a double at byte 22 of format 6) are written as
// given, and the global encoding's bit 0 (table 4) says adjusted standard GPS time when they are;
// without times every GPS time is 0 and the bit is clear. A NaN time is refused.
TEST(LasWriter, GpsTimesAndTheirBaseAreWritten) {
  TempDir dir;
  LasCloud cloud;
  cloud.points = {{0, 0, 0}, {1, 2, 3}, {-4, 5, 6}};
  cloud.gps_time = {3.0e8 + 0.125, 3.0e8 + 0.25, 1.5};
  for (bool adjusted : {true, false}) {
    cloud.adjusted_gps_time = adjusted;
    ASSERT_TRUE(WriteLas(dir / "t.las", cloud).ok());
    const Bytes las{ReadBytes(dir / "t.las")};
    ASSERT_GE(las.data.size(), 375u);
    EXPECT_EQ(las.At<std::uint16_t>(6) & 1u, adjusted ? 1u : 0u);
    EXPECT_EQ(las.At<std::uint8_t>(kFormat), 6);
    const std::uint32_t first = las.At<std::uint32_t>(kOffsetToPoints);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(las.At<double>(first + i * 30 + 22), cloud.gps_time[i]) << i;
  }
  LasCloud untimed;
  untimed.points = cloud.points;
  ASSERT_TRUE(WriteLas(dir / "u.las", untimed).ok());
  const Bytes plain{ReadBytes(dir / "u.las")};
  EXPECT_EQ(plain.At<std::uint16_t>(6) & 1u, 0u);
  const std::uint32_t first = plain.At<std::uint32_t>(kOffsetToPoints);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(plain.At<double>(first + i * 30 + 22), 0.0) << i;
  cloud.gps_time[1] = std::numeric_limits<double>::quiet_NaN();
  const Status nan = WriteLas(dir / "t.las", cloud);
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.error().message.find("point 1 has a GPS time"), std::string::npos) << nan.error().message;
}

TEST(LasWriter, EmptyCloudIsAValidFile) {
  TempDir dir;
  ASSERT_TRUE(WriteLas(dir / "empty.las", LasCloud{}).ok());
  const Bytes las{ReadBytes(dir / "empty.las")};
  EXPECT_EQ(las.data.size(), 375u + 54u);
  EXPECT_EQ(las.At<std::uint64_t>(kPointCount), 0u);
  EXPECT_EQ(las.At<std::uint32_t>(kOffsetToPoints), 375u + 54u);
}

TEST(LasWriter, NanPointIsRejectedAndKeepsThePreviousFile) {
  TempDir dir;
  LasCloud cloud = GeoreferencedCloud(10, 3);
  ASSERT_TRUE(WriteLas(dir / "cloud.las", cloud).ok());
  const std::string previous = ReadBytes(dir / "cloud.las");
  cloud.points[3].y() = std::nan("");
  const Status status = WriteLas(dir / "cloud.las", cloud);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(status.error().message.find("point 3 is not finite"), std::string::npos) << status.error().message;
  EXPECT_NE(status.error().message.find("cloud.las"), std::string::npos) << status.error().message;
  EXPECT_EQ(ReadBytes(dir / "cloud.las"), previous);
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"cloud.las"});  // no temporary file left
}

TEST(LasWriter, MismatchedArraySizesAreRejected) {
  TempDir dir;
  const LasCloud good = GeoreferencedCloud(10, 4);
  LasCloud refl = good, rgb = good, ids = good;
  refl.reflectance.pop_back();
  rgb.rgb.assign(11, {{1, 2, 3}});
  ids.source_ids.resize(3);
  for (const LasCloud* bad : {&refl, &rgb, &ids}) {
    const Status status = WriteLas(dir / "bad.las", *bad);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(status.error().message.find("has 10 points but"), std::string::npos) << status.error().message;
  }
  EXPECT_TRUE(Listing(dir.path()).empty());
}

TEST(LasWriter, SpanBeyondInt32AtTenthMillimetreIsRejected) {
  TempDir dir;
  LasCloud cloud;
  cloud.points = {{500000.0, 5000000.0, 0.0}, {500000.0 + 200000.0, 5000000.5, 1.0}};
  ASSERT_TRUE(WriteLas(dir / "wide.las", cloud).ok());  // 200 km fits
  const Bytes las{ReadBytes(dir / "wide.las")};
  ASSERT_EQ(las.data.size(), 375u + 54u + 2 * 30);
  EXPECT_NEAR(las.At<std::int32_t>(375 + 54 + 30) * 0.0001 + las.At<double>(kOffset), 700000.0, 0.00005);

  cloud.points[1].x() = 500000.0 + 220000.0;
  const Status status = WriteLas(dir / "too_wide.las", cloud);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(status.error().message.find("spans 220.000 km along x"), std::string::npos) << status.error().message;
  EXPECT_FALSE(std::filesystem::exists(dir / "too_wide.las"));
  EXPECT_EQ(Listing(dir.path()), std::vector<std::string>{"wide.las"});
}

TEST(LasWriter, NamesThatDoNotFitAreRejected) {
  TempDir dir;
  LasCloud cloud = GeoreferencedCloud(4, 5);
  cloud.source_names[1] = "two\nlines";
  Status status = WriteLas(dir / "a.las", cloud);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("scan 1 contains a tab or line break"), std::string::npos)
      << status.error().message;

  cloud.source_names.assign(3, std::string(30000, 'n'));  // 90 kB > 65,535 bytes
  status = WriteLas(dir / "a.las", cloud);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().message.find("65,535"), std::string::npos) << status.error().message;
  EXPECT_TRUE(Listing(dir.path()).empty());
}

TEST(LasWriter, UnwritablePathIsAnIoError) {
  TempDir dir;
  const Status status = WriteLas(dir / "missing" / "cloud.las", GeoreferencedCloud(4, 6));
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code, ErrorCode::kIoError);
  EXPECT_NE(status.error().message.find("missing/cloud.las"), std::string::npos) << status.error().message;
  EXPECT_TRUE(Listing(dir.path()).empty());
}

}  // namespace
}  // namespace scanreg::io
