#include "core/io/scan_file.h"

#include <gtest/gtest.h>

#include "core/io/text_parse.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakeRoomScan;
using test::TempDir;

TEST(ScanFile, DispatchesByExtensionCaseInsensitively) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan scan = MakeRoomScan(12, 30, "s");
  for (const char* name : {"a.PTX", "b.Ply", "c.pcd"}) {
    ASSERT_TRUE(WriteScanFile(dir / name, {scan}, progress, cancel).ok()) << name;
    Expected<std::vector<Scan>> back = ReadScanFile(dir / name, progress, cancel);
    ASSERT_TRUE(back.ok()) << back.error().ToString();
    ASSERT_EQ(back->size(), 1u);
    EXPECT_EQ((*back)[0].rows, 12) << name;
    EXPECT_EQ((*back)[0].cols, 30) << name;
    EXPECT_EQ((*back)[0].CountValid(), scan.CountValid()) << name;
  }
  EXPECT_EQ(test::ReadBytes(dir / "b.Ply").substr(0, 4), "ply\n");
  EXPECT_EQ(test::ReadBytes(dir / "a.PTX").substr(0, 6), "30\n12\n");
}

TEST(ScanFile, ClearErrors) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  test::WriteBytes(dir / "scan.xyz", "x");
  Expected<std::vector<Scan>> r = ReadScanFile(dir / "scan.xyz", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("'.xyz'"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find(".ptx, .e57, .ply, .pcd, .las"), std::string::npos) << r.error().message;

  r = ReadScanFile(dir / "missing.ptx", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kNotFound);
  EXPECT_NE(r.error().message.find("missing.ptx"), std::string::npos);

  const Scan scan = MakeRoomScan(4, 6);
  Status s = WriteScanFile(dir / "two.ply", {scan, scan}, progress, cancel);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("one scan"), std::string::npos);
  EXPECT_FALSE(std::filesystem::exists(dir / "two.ply"));
  EXPECT_FALSE(WriteScanFile(dir / "x.las", {scan}, progress, cancel).ok());
  s = WriteScanFile(dir / "no_such_dir" / "x.ptx", {scan}, progress, cancel);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code, ErrorCode::kIoError);
}

TEST(ScanFile, ScanWithoutValidPointsReadsAndSaysSo) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan empty("empty", 3, 4);
  for (const char* name : {"e.ptx", "e.ply", "e.pcd"}) {
    ASSERT_TRUE(WriteScanFile(dir / name, {empty}, progress, cancel).ok()) << name;
    Expected<std::vector<Scan>> back = ReadScanFile(dir / name, progress, cancel);
    ASSERT_TRUE(back.ok()) << name << ": " << back.error().ToString();
    EXPECT_EQ((*back)[0].CountValid(), 0u) << name;
    EXPECT_EQ((*back)[0].rows, 3) << name;
  }
}

TEST(TextParse, NumbersAndLines) {
  float v[4];
  NumberParse p = ParseNumbers("  1.5\t-2e-3 +4 7 8", v, 4);
  EXPECT_EQ(p.status, ParseStatus::kOk);
  ASSERT_EQ(p.count, 4);
  EXPECT_FLOAT_EQ(v[0], 1.5f);
  EXPECT_FLOAT_EQ(v[1], -0.002f);
  EXPECT_FLOAT_EQ(v[2], 4.0f);
  p = ParseNumbers("1 2x 3", v, 4);
  EXPECT_EQ(p.status, ParseStatus::kBadToken);
  EXPECT_EQ(p.token, "2x");
  p = ParseNumbers("1 -inf", v, 4);
  EXPECT_EQ(p.status, ParseStatus::kNonFinite);
  p = ParseNumbers("1e-60 1e60", v, 4);  // float underflow reads as 0; overflow is non-finite
  EXPECT_EQ(p.status, ParseStatus::kNonFinite);
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(v[0], 0.0f);

  LineReader lines("a\r\nb\n\n  \nc");
  std::string_view line;
  ASSERT_TRUE(lines.Next(&line));
  EXPECT_EQ(line, "a");
  ASSERT_TRUE(lines.Next(&line));
  EXPECT_EQ(line, "b");
  EXPECT_EQ(lines.line_number(), 2);
  EXPECT_EQ(lines.CountRemainingLines(), 3u);
  ASSERT_TRUE(lines.SkipBlankLines());
  ASSERT_TRUE(lines.Next(&line));
  EXPECT_EQ(line, "c");
  EXPECT_EQ(lines.line_number(), 5);
  EXPECT_FALSE(lines.Next(&line));

  char buf[32];
  const float f = 0.1f + 1e-7f;
  const std::string text(buf, AppendNumber(buf, f));
  float g = 0;
  ASSERT_EQ(ParseNumbers(text, &g, 1).count, 1);
  EXPECT_EQ(f, g);
}

}  // namespace
}  // namespace scanreg::io
