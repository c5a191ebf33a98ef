// Damaged and malformed E57 files: clear errors naming the file, never a crash.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

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
using test::MakePose;
using test::MakeRoomScan;
using test::PagedBytes;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

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
