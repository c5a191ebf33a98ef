#include "core/io/ptx.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::MakePose;
using test::MakeRoomScan;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

TEST(Ptx, ReadsRealPumpScan) {
  SCANREG_REQUIRE_REALDATA(data);
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = ReadPtx(data / "e57_pumpA_tls/pumpA.ptx", progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  ASSERT_EQ(scans->size(), 1u);
  const Scan& scan = (*scans)[0];
  EXPECT_EQ(scan.name, "pumpA");
  EXPECT_EQ(scan.rows, 1074);
  EXPECT_EQ(scan.cols, 345);
  EXPECT_EQ(scan.CountValid(), 155201u);
  EXPECT_TRUE(scan.world_from_scan.matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-12));
  float refl_min = 1e9f, refl_max = -1e9f, range_min = 1e9f, range_max = -1e9f;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid[i]) continue;
    refl_min = std::min(refl_min, scan.reflectance[i]);
    refl_max = std::max(refl_max, scan.reflectance[i]);
    range_min = std::min(range_min, scan.points[i].norm());
    range_max = std::max(range_max, scan.points[i].norm());
  }
  EXPECT_GE(refl_min, 0.38f);
  EXPECT_LE(refl_max, 0.70f);
  EXPECT_GE(range_min, 1.975f);
  EXPECT_LE(range_max, 5.435f);
  EXPECT_GT(range_max - range_min, 3.0f);
  EXPECT_FALSE(scan.angles.empty());
}

void ExpectSameScan(const Scan& a, const Scan& b) {
  ASSERT_EQ(a.rows, b.rows);
  ASSERT_EQ(a.cols, b.cols);
  ASSERT_EQ(a.valid, b.valid);
  float max_err = 0.0f, max_refl_err = 0.0f;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a.valid[i]) continue;
    max_err = std::max(max_err, (a.points[i] - b.points[i]).norm());
    max_refl_err = std::max(max_refl_err, std::abs(a.reflectance[i] - b.reflectance[i]));
  }
  EXPECT_LE(max_err, 1e-5f);
  EXPECT_LE(max_refl_err, 1e-6f);
  EXPECT_TRUE(a.world_from_scan.matrix().isApprox(b.world_from_scan.matrix(), 1e-12))
      << a.world_from_scan.matrix() << "\nvs\n"
      << b.world_from_scan.matrix();
}

TEST(Ptx, RoundTripOneScanKeepsGridPointsAndPose) {
  TempDir dir;
  Scan scan = MakeRoomScan(40, 90, "room");
  scan.world_from_scan = MakePose(0.7, {0.2, -0.3, 1.0}, {1234.5, -20.25, 3.125});
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WritePtx(dir / "room.ptx", {scan}, progress, cancel).ok());
  Expected<std::vector<Scan>> back = ReadPtx(dir / "room.ptx", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 1u);
  EXPECT_EQ((*back)[0].name, "room");
  ExpectSameScan(scan, (*back)[0]);
  EXPECT_EQ((*back)[0].CountValid(), scan.CountValid());
  EXPECT_LT(scan.CountValid(), scan.size());  // the test has empty cells
  // No temporary file is left beside the target.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(Ptx, RoundTripTwoScansWithDifferentPosesAndInputUntouched) {
  TempDir dir;
  Scan a = MakeRoomScan(30, 60, "a");
  Scan b = MakeRoomScan(20, 48, "b");
  a.world_from_scan = MakePose(0.3, {0, 0, 1}, {5.0, 2.0, 0.5});
  b.world_from_scan = MakePose(-1.2, {0.1, 0.2, 1.0}, {-3.0, 7.5, 1.25});
  NullProgress progress;
  CancelToken cancel;
  ASSERT_TRUE(WritePtx(dir / "pair.ptx", {a, b}, progress, cancel).ok());
  const std::string bytes_before = ReadBytes(dir / "pair.ptx");
  const auto mtime_before = std::filesystem::last_write_time(dir / "pair.ptx");
  Expected<std::vector<Scan>> back = ReadPtx(dir / "pair.ptx", progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  ASSERT_EQ(back->size(), 2u);
  EXPECT_EQ((*back)[0].name, "pair_1");
  EXPECT_EQ((*back)[1].name, "pair_2");
  ExpectSameScan(a, (*back)[0]);
  ExpectSameScan(b, (*back)[1]);
  // Re-writing what was read to another file leaves the input as it was.
  ASSERT_TRUE(WritePtx(dir / "copy.ptx", *back, progress, cancel).ok());
  EXPECT_EQ(ReadBytes(dir / "pair.ptx"), bytes_before);
  EXPECT_EQ(std::filesystem::last_write_time(dir / "pair.ptx"), mtime_before);
  EXPECT_EQ(ReadBytes(dir / "copy.ptx"), bytes_before);  // and the writer is deterministic
}

// A valid 2-column x 3-row scan: header lines 1-10, point lines 11-16.
std::vector<std::string> SmallPtxLines() {
  return {"2",         "3",           "0 0 0",     "1 0 0",       "0 1 0",
          "0 0 1",     "1 0 0 0",     "0 1 0 0",   "0 0 1 0",     "0 0 0 1",
          "1 0 0 0.5", "1 0.1 0 0.5", "0 0 0 0.5", "1 0 0.1 0.5", "1 0.1 0.1 0.5 10 20 30",
          "2 0 0 0.25"};
}

std::string Join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

struct BadCase {
  std::string name;
  int line_to_change;  // 1-based; 0 = none
  std::string replacement;
  bool drop_last = false;
  std::string expect_line;   // "line N"
  std::string expect_words;  // part of the explanation
};

TEST(Ptx, SmallFileReads) {
  TempDir dir;
  WriteBytes(dir / "small.ptx", Join(SmallPtxLines()));
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = ReadPtx(dir / "small.ptx", progress, cancel);
  ASSERT_TRUE(scans.ok()) << scans.error().ToString();
  const Scan& s = (*scans)[0];
  EXPECT_EQ(s.rows, 3);
  EXPECT_EQ(s.cols, 2);
  EXPECT_EQ(s.CountValid(), 5u);
  EXPECT_FALSE(s.IsValid(2, 0));                                     // line 13: third row of column 0
  EXPECT_TRUE(s.Point(1, 0).isApprox(Eigen::Vector3f(1, 0.1f, 0)));  // line 12
  EXPECT_TRUE(s.Point(1, 1).isApprox(Eigen::Vector3f(1, 0.1f, 0.1f)));
  EXPECT_FLOAT_EQ(s.Reflectance(2, 1), 0.25f);
}

TEST(Ptx, MalformedFilesNameFileAndLine) {
  const std::vector<BadCase> cases = {
      {"truncated", 0, "", true, "line 16", "truncated"},
      {"bad_token", 13, "1 2 abc 0.5", false, "line 13", "'abc' is not a number"},
      {"nan", 14, "nan 1 1 0.5", false, "line 14", "NaN"},
      {"inf", 11, "1 inf 1 0.5", false, "line 11", "NaN or infinite"},
      {"three_numbers", 12, "1 2 3", false, "line 12", "found 3"},
      {"absurd_rows", 2, "2000000", false, "line 1", "impossible scan size"},
      {"zero_cols", 1, "0", false, "line 1", "impossible scan size"},
      {"fraction_cols", 1, "2.5", false, "line 1", "impossible scan size"},
      {"non_rotation_axes", 5, "0 2 0", false, "line 4", "not a rotation"},
      {"reflection_axes", 6, "0 0 -1", false, "line 4", "not a rotation"},
      {"non_rigid_transform", 8, "0 1 0 0.5", false, "line 7", "not rigid"},
      {"header_token", 3, "0 zero 0", false, "line 3", "'zero' is not a number"},
  };
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  for (const BadCase& c : cases) {
    std::vector<std::string> lines = SmallPtxLines();
    if (c.line_to_change > 0) lines[c.line_to_change - 1] = c.replacement;
    if (c.drop_last) lines.pop_back();
    const auto path = dir / (c.name + ".ptx");
    WriteBytes(path, Join(lines));
    Expected<std::vector<Scan>> r = ReadPtx(path, progress, cancel);
    ASSERT_FALSE(r.ok()) << c.name;
    const std::string& msg = r.error().message;
    EXPECT_EQ(r.error().code, ErrorCode::kParseError) << c.name;
    EXPECT_NE(msg.find(c.name + ".ptx"), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.expect_line + ":"), std::string::npos) << c.name << ": " << msg;
    EXPECT_NE(msg.find(c.expect_words), std::string::npos) << c.name << ": " << msg;
  }
}

TEST(Ptx, EmptyFileAndTruncatedSecondScan) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  WriteBytes(dir / "empty.ptx", "");
  Expected<std::vector<Scan>> r = ReadPtx(dir / "empty.ptx", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("empty.ptx, line 1:"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("empty"), std::string::npos);

  WriteBytes(dir / "blank.ptx", "\n  \n");
  EXPECT_FALSE(ReadPtx(dir / "blank.ptx", progress, cancel).ok());

  // Two scans; the second lacks its last 2 of 6 point lines: lines 17-26 header, 27-30 points.
  std::vector<std::string> lines = SmallPtxLines();
  std::vector<std::string> second = SmallPtxLines();
  second.resize(second.size() - 2);
  lines.insert(lines.end(), second.begin(), second.end());
  WriteBytes(dir / "two.ptx", Join(lines));
  r = ReadPtx(dir / "two.ptx", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("two.ptx, line 31:"), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("4 of 6 point lines of scan 2"), std::string::npos) << r.error().message;

  // A header claiming a huge grid in a short file fails fast as truncated, without allocating it.
  lines = SmallPtxLines();
  lines[0] = "100000";
  lines[1] = "4000";
  WriteBytes(dir / "huge.ptx", Join(lines));
  r = ReadPtx(dir / "huge.ptx", progress, cancel);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("huge.ptx, line 17:"), std::string::npos) << r.error().message;
}

TEST(Ptx, ReportsProgressAndHonoursCancel) {
  TempDir dir;
  NullProgress null_progress;
  CancelToken cancel;
  ASSERT_TRUE(WritePtx(dir / "p.ptx", {MakeRoomScan(100, 200)}, null_progress, cancel).ok());
  std::atomic<int> calls{0};
  double last = -1.0;
  bool monotone = true;
  CallbackProgress progress([&](double f, const std::string&) {
    ++calls;
    monotone = monotone && f >= last;
    last = f;
  });
  ASSERT_TRUE(ReadPtx(dir / "p.ptx", progress, cancel).ok());
  EXPECT_GE(calls.load(), 10);
  EXPECT_LE(calls.load(), 200);
  EXPECT_TRUE(monotone);
  EXPECT_DOUBLE_EQ(last, 1.0);

  CancelToken cancelled;
  cancelled.Cancel();
  Expected<std::vector<Scan>> r = ReadPtx(dir / "p.ptx", null_progress, cancelled);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kCancelled);
  const Status w = WritePtx(dir / "q.ptx", {MakeRoomScan(10, 20)}, null_progress, cancelled);
  ASSERT_FALSE(w.ok());
  EXPECT_EQ(w.error().code, ErrorCode::kCancelled);
  EXPECT_FALSE(std::filesystem::exists(dir / "q.ptx"));
}

TEST(Ptx, WriterRejectsNonFinitePointsAndKeepsOldFile) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  WriteBytes(dir / "keep.ptx", "old content");
  Scan scan = MakeRoomScan(5, 8);
  scan.points[scan.Index(2, 2)] = Eigen::Vector3f(std::nanf(""), 0, 0);
  scan.valid[scan.Index(2, 2)] = 1;
  EXPECT_FALSE(WritePtx(dir / "keep.ptx", {scan}, progress, cancel).ok());
  EXPECT_EQ(ReadBytes(dir / "keep.ptx"), "old content");
}

}  // namespace
}  // namespace scanreg::io
