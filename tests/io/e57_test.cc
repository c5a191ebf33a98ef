#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>

#include "core/io/e57_bitpack.h"
#include "core/io/e57_pages.h"
#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/ptx.h"
#include "core/io/scan_file.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakePose;
using test::MakeRoomScan;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

// The logical bytes of an E57 file (checksums dropped) and back (checksums recomputed), so tests
// can damage the content behind valid checksums.
std::string LogicalBytes(const std::string& file) {
  std::string out;
  for (std::size_t p = 0; p + e57::kPageSize <= file.size(); p += e57::kPageSize) out.append(file, p, e57::kPageData);
  return out;
}

std::string PagedBytes(const std::string& logical) {
  std::string out;
  for (std::size_t p = 0; p < logical.size(); p += e57::kPageData) {
    std::string page = logical.substr(p, e57::kPageData);
    page.resize(e57::kPageData, '\0');
    const std::uint32_t crc = e57::Crc32c(page.data(), page.size());
    for (int i = 0; i < 4; ++i) page.push_back(static_cast<char>((crc >> (24 - 8 * i)) & 0xFF));
    out += page;
  }
  return out;
}

// The file with its XML section (the last thing our writer puts in a file) replaced by
// edit(xml), lengths and checksums updated.
std::string WithXml(const std::string& file, const std::function<std::string(std::string)>& edit) {
  std::string logical = LogicalBytes(file);
  std::uint64_t xml_offset = 0, xml_length = 0;
  std::memcpy(&xml_offset, &logical[24], 8);
  std::memcpy(&xml_length, &logical[32], 8);
  const std::uint64_t start = e57::LogicalFromPhysical(xml_offset);
  const std::string xml = edit(logical.substr(start, xml_length));
  logical.resize(start);
  logical += xml;
  xml_length = xml.size();
  const std::uint64_t physical_length = (logical.size() + e57::kPageData - 1) / e57::kPageData * e57::kPageSize;
  std::memcpy(&logical[32], &xml_length, 8);
  std::memcpy(&logical[16], &physical_length, 8);
  return PagedBytes(logical);
}

// Replaces every `from` by `to` in the file's XML.
std::string EditXml(const std::string& file, const std::string& from, const std::string& to) {
  return WithXml(file, [&](std::string xml) {
    EXPECT_NE(xml.find(from), std::string::npos) << from;
    for (std::size_t at = xml.find(from); at != std::string::npos; at = xml.find(from, at + to.size()))
      xml.replace(at, from.size(), to);
    return xml;
  });
}

bool Has(const std::string& message, const std::string& part) { return message.find(part) != std::string::npos; }

std::vector<Scan> TwoPosedScans() {
  Scan a = MakeRoomScan(40, 90, "station A");
  a.world_from_scan = MakePose(0.7, {0.2, -0.3, 1.0}, {412345.125, 5523456.75, 312.0625});
  Scan b = MakeRoomScan(25, 60, "station <B> & co");
  b.world_from_scan = MakePose(-2.9, {0.0, 0.1, 1.0}, {-3.5, 17.25, 0.001});
  return {a, b};
}

void ExpectSameScan(const Scan& want, const Scan& got) {
  EXPECT_EQ(got.name, want.name);
  ASSERT_EQ(got.rows, want.rows);
  ASSERT_EQ(got.cols, want.cols);
  ASSERT_EQ(got.valid, want.valid);
  float max_err = 0.0f, max_refl_err = 0.0f;
  for (std::size_t i = 0; i < want.size(); ++i) {
    if (!want.valid[i]) continue;
    max_err = std::max(max_err, (want.points[i] - got.points[i]).norm());
    max_refl_err = std::max(max_refl_err, std::abs(want.reflectance[i] - got.reflectance[i]));
  }
  EXPECT_EQ(max_err, 0.0f);  // Float single stores the scan's own floats
  EXPECT_LE(max_refl_err, 1e-7f);
  EXPECT_LE((want.world_from_scan.linear() - got.world_from_scan.linear()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((want.world_from_scan.translation() - got.world_from_scan.translation()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_FALSE(got.angles.empty());
}

TEST(E57, ChecksumAndBitPackingFollowTheStandard) {
  EXPECT_EQ(e57::Crc32c("123456789", 9), 0xE3069283u);  // the CRC-32C check value
  EXPECT_EQ(e57::BitWidth(0, 0), 0);
  EXPECT_EQ(e57::BitWidth(0, 1073), 11);
  EXPECT_EQ(e57::BitWidth(-8388608, 8388607), 24);
  EXPECT_EQ(e57::BitWidth(std::numeric_limits<std::int64_t>::min(), std::numeric_limits<std::int64_t>::max()), 64);
  // LSB first: 3 (2 bits) then 5 (3 bits) then 1 (1 bit) = 0b1'101'11 in the first byte.
  e57::BitWriter w;
  w.Write(3, 2), w.Write(5, 3), w.Write(1, 1);
  EXPECT_EQ(w.Take(true), std::string(1, char(0x37)));
  // Every width 1..64, values split across pieces of 1..7 bytes, as across data packets.
  std::mt19937_64 rng(3);
  std::vector<std::pair<std::uint64_t, int>> values;
  for (int k = 0; k < 2000; ++k) {
    const int bits = 1 + k % 64;
    values.emplace_back(rng() & (~std::uint64_t(0) >> (64 - bits)), bits);
    w.Write(values.back().first, bits);
  }
  const std::string bytes = w.Take(true);
  e57::BitReader r;
  std::size_t fed = 0, read = 0;
  for (const auto& [value, bits] : values) {
    std::uint64_t got = 0;
    while (!r.Read(bits, &got)) {
      ASSERT_LT(fed, bytes.size());
      const std::size_t piece = std::min<std::size_t>(1 + fed % 7, bytes.size() - fed);
      r.Append(std::string_view(bytes).substr(fed, piece));
      fed += piece;
    }
    ASSERT_EQ(got, value) << "value " << read << ", " << bits << " bits";
    ++read;
  }
  EXPECT_EQ(read, values.size());
}

TEST(E57, RoundTripKeepsGridPointsReflectanceAndPoses) {
  TempDir dir;
  const std::vector<Scan> scans = TwoPosedScans();
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WriteE57(dir / "two.e57", scans, progress, cancel).ok());
  const std::string bytes = ReadBytes(dir / "two.e57");
  EXPECT_EQ(bytes.substr(0, 8), "ASTM-E57");
  EXPECT_EQ(bytes.size() % 1024, 0u);
  Expected<std::vector<Scan>> back = ReadE57(dir / "two.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  ExpectSameScan(scans[0], (*back)[0]);
  ExpectSameScan(scans[1], (*back)[1]);
  EXPECT_LT(scans[0].CountValid(), scans[0].size());                                 // the test has empty cells
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 1);  // no temporary left
}

TEST(E57, ScanFileDispatchKeepsSeveralScans) {
  TempDir dir;
  const std::vector<Scan> scans = TwoPosedScans();
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WriteScanFile(dir / "two.E57", scans, progress, cancel).ok());
  Expected<std::vector<Scan>> back = ReadScanFile(dir / "two.E57", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  EXPECT_EQ((*back)[1].CountValid(), scans[1].CountValid());
}

TEST(E57, ListsScansAndReadsChosenOnes) {
  TempDir dir;
  const std::vector<Scan> scans = TwoPosedScans();
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WriteE57(dir / "two.e57", scans, progress, cancel).ok());
  Expected<std::vector<E57ScanInfo>> list = ListE57Scans(dir / "two.e57");
  ASSERT_TRUE(list.ok()) << list.error().ToString();
  ASSERT_EQ(list->size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ((*list)[i].name, scans[i].name);
    EXPECT_EQ((*list)[i].points, scans[i].CountValid());
    EXPECT_EQ((*list)[i].rows, scans[i].rows);
    EXPECT_EQ((*list)[i].cols, scans[i].cols);
    EXPECT_TRUE((*list)[i].has_intensity);
    EXPECT_TRUE((*list)[i].has_pose);
  }
  E57ReadOptions by_name;
  by_name.names = {"station <B> & co"};
  Expected<std::vector<Scan>> b = ReadE57(dir / "two.e57", by_name, progress, cancel);
  ASSERT_TRUE(b.ok()) << b.error().ToString();
  ASSERT_EQ(b->size(), 1u);
  ExpectSameScan(scans[1], (*b)[0]);
  E57ReadOptions by_index;
  by_index.indices = {0};
  Expected<std::vector<Scan>> a = ReadE57(dir / "two.e57", by_index, progress, cancel);
  ASSERT_TRUE(a.ok()) << a.error().ToString();
  ASSERT_EQ(a->size(), 1u);
  EXPECT_EQ((*a)[0].name, "station A");

  by_name.names = {"station C"};
  Expected<std::vector<Scan>> none = ReadE57(dir / "two.e57", by_name, progress, cancel);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.error().code, ErrorCode::kNotFound);
  EXPECT_NE(none.error().message.find("'station C'"), std::string::npos) << none.error().message;
  by_index.indices = {2};
  EXPECT_FALSE(ReadE57(dir / "two.e57", by_index, progress, cancel).ok());
}

TEST(E57, ScanWithoutValidPointKeepsItsGrid) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const std::vector<Scan> scans = {Scan("empty", 5, 7), MakeRoomScan(12, 20, "room")};
  ASSERT_TRUE(WriteE57(dir / "a.e57", scans, progress, cancel).ok());
  Expected<std::vector<Scan>> back = ReadE57(dir / "a.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  EXPECT_EQ((*back)[0].rows, 5);
  EXPECT_EQ((*back)[0].cols, 7);
  EXPECT_EQ((*back)[0].CountValid(), 0u);
  EXPECT_EQ((*back)[1].CountValid(), scans[1].CountValid());
  // Bounds of an empty scan are all there is to check.
  WriteBytes(dir / "b.e57", EditXml(ReadBytes(dir / "a.e57"), ">4</rowMaximum>", ">-3</rowMaximum>"));
  Expected<std::vector<Scan>> bad = ReadE57(dir / "b.e57", {}, progress, cancel);
  ASSERT_FALSE(bad.ok());
  EXPECT_TRUE(Has(bad.error().message, "impossible grid of -2 rows x 7 columns")) << bad.error().message;
}

TEST(E57, CancelStopsReadingAndWriting) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan scan = MakeRoomScan(40, 90);
  ASSERT_TRUE(WriteE57(dir / "a.e57", {scan}, progress, cancel).ok());
  cancel.Cancel();
  Expected<std::vector<Scan>> r = ReadE57(dir / "a.e57", {}, progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kCancelled);
  Status w = WriteE57(dir / "b.e57", {scan}, progress, cancel);
  ASSERT_FALSE(w.ok());
  EXPECT_EQ(w.error().code, ErrorCode::kCancelled);
  EXPECT_FALSE(std::filesystem::exists(dir / "b.e57"));
}

TEST(E57, RealPumpScanMatchesItsPtxPointForPoint) {
  SCANREG_REQUIRE_REALDATA(data);
  const auto e57_path = data / "e57_pumpA_tls/pumpAVisualReferenceImage.e57";
  Expected<std::vector<E57ScanInfo>> list = ListE57Scans(e57_path);
  ASSERT_TRUE(list.ok()) << list.error().ToString();
  ASSERT_EQ(list->size(), 1u);
  EXPECT_EQ((*list)[0].name, "pumpA");
  EXPECT_EQ((*list)[0].points, 155201u);
  EXPECT_EQ((*list)[0].rows, 1074);
  EXPECT_EQ((*list)[0].cols, 345);
  EXPECT_TRUE((*list)[0].has_intensity);
  EXPECT_FALSE((*list)[0].has_pose);

  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> e57 = ReadE57(e57_path, {}, progress, cancel);
  ASSERT_TRUE(e57.ok()) << e57.error().ToString();
  Expected<std::vector<Scan>> ptx = ReadPtx(data / "e57_pumpA_tls/pumpA.ptx", progress, cancel);
  ASSERT_TRUE(ptx.ok()) << ptx.error().ToString();
  ASSERT_EQ(e57->size(), 1u);
  const Scan& got = (*e57)[0];
  const Scan& want = (*ptx)[0];
  EXPECT_EQ(got.name, "pumpA");
  ASSERT_EQ(got.rows, 1074);
  ASSERT_EQ(got.cols, 345);
  EXPECT_EQ(got.CountValid(), 155201u);
  ASSERT_EQ(got.valid, want.valid);
  EXPECT_TRUE(got.world_from_scan.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-15));
  double max_err = 0.0, max_refl_err = 0.0;
  float refl_min = 1.0f, refl_max = 0.0f;
  for (std::size_t i = 0; i < got.size(); ++i) {
    if (!got.valid[i]) continue;
    max_err = std::max(max_err, double((got.points[i] - want.points[i]).norm()));
    max_refl_err = std::max(max_refl_err, double(std::abs(got.reflectance[i] - want.reflectance[i])));
    refl_min = std::min(refl_min, got.reflectance[i]), refl_max = std::max(refl_max, got.reflectance[i]);
  }
  EXPECT_LE(max_err, 1e-7);       // 1e-6 m ScaledInteger steps; the PTX was written from the same integers
  EXPECT_LE(max_refl_err, 2e-6);  // intensity 0..32767 scaled to [0, 1] by intensityLimits
  EXPECT_GE(refl_min, 0.38f);
  EXPECT_LE(refl_max, 0.70f);
  EXPECT_FALSE(got.angles.empty());
}

// Writes a small scan and returns its file's bytes.
std::string SmallFile(const TempDir& dir) {
  NullProgress progress;
  CancelToken cancel;
  Scan scan = MakeRoomScan(12, 20, "small");
  scan.world_from_scan = MakePose(0.3, {0, 0, 1}, {1, 2, 3});
  EXPECT_TRUE(WriteE57(dir / "small.e57", {scan}, progress, cancel).ok());
  return ReadBytes(dir / "small.e57");
}

// Reads bytes written to a file; returns the error message, or "" when the read succeeded.
std::string ReadError(const TempDir& dir, const std::string& bytes) {
  WriteBytes(dir / "bad.e57", bytes);
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> r = ReadE57(dir / "bad.e57", {}, progress, cancel);
  if (r.ok()) {
    for (const Scan& s : *r) EXPECT_TRUE(s.Validate().ok());
    return "";
  }
  EXPECT_NE(r.error().message.find("bad.e57"), std::string::npos) << r.error().message;
  return r.error().message;
}

TEST(E57, ReadsSphericalCoordinates) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  // Write (range, azimuth, elevation) in the cartesian fields, then rename the fields.
  Scan stored("sph", 10, 30);
  for (int r = 0; r < stored.rows; ++r)
    for (int c = 0; c < stored.cols; ++c)
      stored.Set(r, c, {2.0f + 0.01f * c, -1.0f + 0.05f * c, 0.4f - 0.07f * r}, 0.5f);
  ASSERT_TRUE(WriteE57(dir / "a.e57", {stored}, progress, cancel).ok());
  std::string bytes = ReadBytes(dir / "a.e57");
  bytes = EditXml(bytes, "<cartesianX ", "<sphericalRange ");
  bytes = EditXml(bytes, "<cartesianY ", "<sphericalAzimuth ");
  bytes = EditXml(bytes, "<cartesianZ ", "<sphericalElevation ");
  WriteBytes(dir / "sph.e57", bytes);
  Expected<std::vector<Scan>> back = ReadE57(dir / "sph.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  const Scan& got = (*back)[0];
  ASSERT_EQ(got.valid, stored.valid);
  double max_err = 0.0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const Eigen::Vector3d s = stored.points[i].cast<double>();  // range, azimuth, elevation
    const Eigen::Vector3d want(s[0] * std::cos(s[2]) * std::cos(s[1]), s[0] * std::cos(s[2]) * std::sin(s[1]),
                               s[0] * std::sin(s[2]));
    max_err = std::max(max_err, (got.points[i].cast<double>() - want).norm());
  }
  EXPECT_LE(max_err, 1e-6);
}

TEST(E57, ScanWithoutGridIsOrganizedAndIntensityUsesItsLimits) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan scan = MakeRoomScan(30, 80, "room");
  ASSERT_TRUE(WriteE57(dir / "a.e57", {scan}, progress, cancel).ok());
  const std::string bytes = ReadBytes(dir / "a.e57");

  WriteBytes(dir / "limits.e57",
             EditXml(bytes, "<intensityMaximum type=\"Float\">1<", "<intensityMaximum type=\"Float\">2<"));
  Expected<std::vector<Scan>> halved = ReadE57(dir / "limits.e57", {}, progress, cancel);
  ASSERT_TRUE(halved.ok()) << halved.error().ToString();
  float max_err = 0.0f;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) max_err = std::max(max_err, std::abs((*halved)[0].reflectance[i] - scan.reflectance[i] / 2));
  EXPECT_LE(max_err, 1e-7f);

  WriteBytes(dir / "cloud.e57", EditXml(EditXml(bytes, "<rowIndex ", "<rowIndeX "), "<columnIndex ", "<columnIndeX "));
  Expected<std::vector<E57ScanInfo>> list = ListE57Scans(dir / "cloud.e57");
  ASSERT_TRUE(list.ok());
  EXPECT_EQ((*list)[0].rows, 0);  // no grid
  Expected<std::vector<Scan>> cloud = ReadE57(dir / "cloud.e57", {}, progress, cancel);
  ASSERT_TRUE(cloud.ok()) << cloud.error().ToString();
  const std::size_t n = scan.CountValid(), kept = (*cloud)[0].CountValid();
  EXPECT_LE(kept, n);
  EXPECT_GE(kept, n * 9 / 10);  // organizing by density keeps most points in a cell of their own
}

TEST(E57, ReadsScaledIntegersAndInvalidState) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Scan scan = MakeRoomScan(20, 40, "room");
  for (std::size_t i = 0; i < scan.size(); ++i) scan.reflectance[i] = (i % 3 == 0) ? 2.0f : 0.0f;
  ASSERT_TRUE(WriteE57(dir / "a.e57", {scan}, progress, cancel).ok());
  // Read the 32 bits of each cartesianX float as a ScaledInteger (raw = minimum + bits), and the
  // intensity stream as cartesianInvalidState (0 valid, 2 no coordinates).
  std::string bytes = EditXml(ReadBytes(dir / "a.e57"), "<cartesianX type=\"Float\" precision=\"single\"",
                              "<cartesianX type=\"ScaledInteger\" minimum=\"-5\" maximum=\"4294967290\" "
                              "scale=\"0.5\" offset=\"3\"");
  bytes = EditXml(bytes, "<intensity ", "<cartesianInvalidState ");
  WriteBytes(dir / "b.e57", bytes);
  Expected<std::vector<Scan>> back = ReadE57(dir / "b.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  const Scan& got = (*back)[0];
  std::size_t valid = 0;
  double max_rel_err = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const bool want_valid = scan.valid[i] && scan.reflectance[i] == 0.0f;
    ASSERT_EQ(got.valid[i] != 0, want_valid) << "cell " << i;
    if (!want_valid) continue;
    ++valid;
    std::uint32_t bits;
    std::memcpy(&bits, &scan.points[i].x(), 4);
    const double want_x = (double(bits) - 5.0) * 0.5 + 3.0;
    // x ~ 1e9 m is far from the origin: the reader moves a whole-metre shift into the pose.
    const Eigen::Vector3d world = got.world_from_scan * got.points[i].cast<double>();
    max_rel_err = std::max(max_rel_err, std::abs(world.x() - want_x) / want_x);
    EXPECT_NEAR(world.y(), scan.points[i].y(), 1e-6);
    EXPECT_EQ(got.reflectance[i], 0.5f);  // no intensity field left
  }
  EXPECT_GT(valid, scan.CountValid() / 2);
  EXPECT_GT(got.world_from_scan.translation().norm(), 1e8);
  EXPECT_LE(max_rel_err, 3e-7);  // a few float ulps: the points stay float, ~1e9 here
}

TEST(E57, SkipsIndexAndEmptyPackets) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan scan = MakeRoomScan(30, 80, "room");
  ASSERT_TRUE(WriteE57(dir / "a.e57", {scan}, progress, cancel).ok());
  // Our writer puts the one section at logical byte 48 (header 32 bytes, then data packets) and
  // the XML last. Put an index packet (16-byte header, one entry) and an empty packet before the
  // data packets; the section and everything after it grow by 36 bytes.
  std::string logical = LogicalBytes(ReadBytes(dir / "a.e57"));
  std::string index(32, '\0');
  index[0] = 0, index[2] = 31, index[4] = 1;  // type, length - 1, entryCount
  const std::string empty = std::string("\x02\x00\x03\x00", 4);
  logical.insert(48 + 32, index + empty);
  std::uint64_t section_length = 0, xml_offset = 0;
  std::memcpy(&section_length, &logical[48 + 8], 8);
  std::memcpy(&xml_offset, &logical[24], 8);
  section_length += 36;
  xml_offset = e57::PhysicalFromLogical(e57::LogicalFromPhysical(xml_offset) + 36);
  const std::uint64_t physical_length = (logical.size() + e57::kPageData - 1) / e57::kPageData * e57::kPageSize;
  std::memcpy(&logical[48 + 8], &section_length, 8);
  std::memcpy(&logical[24], &xml_offset, 8);
  std::memcpy(&logical[16], &physical_length, 8);
  WriteBytes(dir / "b.e57", PagedBytes(logical));
  Expected<std::vector<Scan>> back = ReadE57(dir / "b.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_EQ((*back)[0].valid, scan.valid);
  EXPECT_EQ((*back)[0].points, scan.points);

  logical[48 + 32] = 7;  // an unknown packet type
  WriteBytes(dir / "c.e57", PagedBytes(logical));
  Expected<std::vector<Scan>> bad = ReadE57(dir / "c.e57", {}, progress, cancel);
  ASSERT_FALSE(bad.ok());
  EXPECT_TRUE(Has(bad.error().message, "packet at byte 32 of the points section: unknown packet type 7"))
      << bad.error().message;
}

TEST(E57, MalformedFilesGiveClearErrors) {
  TempDir dir;
  const std::string good = SmallFile(dir);
  ASSERT_EQ(ReadError(dir, good), "");
  EXPECT_EQ(ReadError(dir, PagedBytes(LogicalBytes(good))), "");  // the test's re-paging is faithful

  std::string flipped = good;
  flipped[1024 + 100] ^= 0x10;
  EXPECT_TRUE(Has(ReadError(dir, flipped), "page 1 (physical offset 1024")) << ReadError(dir, flipped);
  EXPECT_TRUE(Has(ReadError(dir, flipped), "CRC-32C"));
  EXPECT_TRUE(Has(ReadError(dir, good.substr(0, good.size() - 1024)), "truncated"));
  EXPECT_TRUE(Has(ReadError(dir, good.substr(0, good.size() - 100)), "truncated"));
  EXPECT_TRUE(Has(ReadError(dir, good.substr(0, 500)), "truncated"));
  EXPECT_TRUE(Has(ReadError(dir, "PLY not e57" + std::string(2000, ' ')), "not an E57 file"));

  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "data3D", "dataXX")), "no data3D element"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(EditXml(good, "<points ", "<pointz "), "</points>", "</pointz>")),
                  "no 'points' element"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "\"CompressedVector\"", "\"CompressedVectoR\"")),
                  "'points' is not a CompressedVector"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "</e57Root>", "</e57Root")), "not valid XML"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "<cartesianY ", "<cartesianQ ")), "neither cartesianX/Y/Z"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "maximum=\"11\"", "maximum=\"-1\"")), "is larger than maximum"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, ">11</rowMaximum>", ">-3</rowMaximum>")), "indexBounds"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, ">11</rowMaximum>", ">9999999</rowMaximum>")), "impossible grid"));
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, "precision=\"single\"", "precision=\"singlE\"")), "precision"));
  const std::string count = "recordCount=\"" + std::to_string(MakeRoomScan(12, 20).CountValid()) + "\"";
  EXPECT_TRUE(Has(ReadError(dir, EditXml(good, count, "recordCount=\"100000\"")), "recordCount 100000 is more"));

  // A NaN coordinate: the first cartesianX of the first data packet (section header 32 bytes,
  // packet header 6 + 6 * 2 bytes, after the 48-byte file header).
  std::string logical = LogicalBytes(good);
  const float nan = std::nanf("");
  std::memcpy(&logical[48 + 32 + 18], &nan, 4);
  EXPECT_TRUE(Has(ReadError(dir, PagedBytes(logical)), "NaN")) << ReadError(dir, PagedBytes(logical));
}

TEST(E57, DamagedBytesNeverCrash) {
  TempDir dir;
  const std::string good = SmallFile(dir);
  const std::string logical = LogicalBytes(good);
  std::mt19937 rng(7);
  int errors = 0, reads = 0;
  for (int k = 0; k < 200; ++k) {  // flip bytes behind valid checksums: exercises every parser
    std::string damaged = logical;
    const int flips = 1 + k % 3;
    for (int f = 0; f < flips; ++f) damaged[rng() % damaged.size()] ^= static_cast<char>(1 + rng() % 255);
    (ReadError(dir, PagedBytes(damaged)).empty() ? reads : errors)++;
  }
  for (std::size_t cut = 0; cut < good.size(); cut += 97) {
    EXPECT_FALSE(ReadError(dir, good.substr(0, cut)).empty()) << "cut at " << cut;
  }
  EXPECT_GT(errors, 0);
  EXPECT_EQ(errors + reads, 200);
}

}  // namespace
}  // namespace scanreg::io
