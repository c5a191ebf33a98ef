// E57 point encodings the writer does not produce: spherical coordinates, ScaledInteger,
// invalid states, scans without grid, intensity limits, index and empty packets.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/io/e57_pages.h"
#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "tests/io/e57_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::EditXml;
using test::Has;
using test::LogicalBytes;
using test::MakeRoomScan;
using test::PagedBytes;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

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

}  // namespace
}  // namespace scanreg::io
