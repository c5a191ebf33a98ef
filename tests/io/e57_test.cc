// E57: round trips, scan lists and choices, the real pumpA file against its PTX.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/io/e57_bitpack.h"
#include "core/io/e57_pages.h"
#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/ptx.h"
#include "core/io/scan_file.h"
#include "tests/io/e57_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::EditXml;
using test::Has;
using test::MakePose;
using test::MakeRoomScan;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

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

}  // namespace
}  // namespace scanreg::io
