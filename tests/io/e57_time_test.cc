// A time per point in E57 (issue 34): written as the timeStamp field, counted from the scan's
// acquisitionStart (ASTM E2807 §8.4.3) when the times are GPS times, and read back in the base they
// came in. The file is checked by decoding it as the standard lays it out (pages, XML, the points
// section's packets; test::DecodeE57BySpecification), not only with our reader.
#include <gtest/gtest.h>
#include <pugixml.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <tuple>
#include <string>
#include <vector>

#include "core/io/e57_reader.h"
#include "core/io/e57_writer.h"
#include "core/io/las_reader.h"
#include "tests/io/e57_test_util.h"
#include "tests/io/io_test_util.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

using test::Has;
using test::LogicalBytes;
using test::PagedBytes;
using test::ReadBytes;
using test::TempDir;
using test::WriteBytes;

// A 6 x 8 grid and 5 more points in a list (second returns): no grid in the file, every field a
// Float. Times 0.25 ms apart from `first`, in `base`.
Scan TimedScan(double first, const std::string& base) {
  Scan scan("timed", 6, 8);
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c) scan.Set(r, c, {3.0f + 0.1f * c, 0.2f * r - 0.5f, 1.0f + 0.01f * c * r}, 0.4f);
  for (int k = 0; k < 5; ++k) {
    scan.list_points.push_back({5.0f + k, -1.0f, 0.5f});
    scan.list_reflectance.push_back(0.6f);
  }
  scan.AddTime();
  for (std::size_t i = 0; i < scan.size(); ++i) scan.time[i] = first + 2.5e-4 * double(i);
  for (std::size_t k = 0; k < scan.list_time.size(); ++k) scan.list_time[k] = first + 1.0 + 2.5e-4 * double(k);
  scan.time_base = base;
  return scan;
}

// Each written point's time, looked up by its coordinates.
std::map<std::tuple<float, float, float>, double> TimesByPoint(const Scan& scan) {
  std::map<std::tuple<float, float, float>, double> out;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) out[{scan.points[i].x(), scan.points[i].y(), scan.points[i].z()}] = scan.time[i];
  for (std::size_t k = 0; k < scan.list_points.size(); ++k)
    out[{scan.list_points[k].x(), scan.list_points[k].y(), scan.list_points[k].z()}] = scan.list_time[k];
  return out;
}

TEST(E57Time, GpsTimesAreTimeStampsFromTheScansAcquisitionStart) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const double first = 3.2e8 + 1234.56789;  // adjusted standard GPS time (2019-ish)
  const Scan scan = TimedScan(first, kAdjustedGpsTime);
  ASSERT_TRUE(WriteE57(dir / "t.e57", {scan}, progress, cancel).ok());

  const test::E57BySpecification d = test::DecodeE57BySpecification(ReadBytes(dir / "t.e57"));
  ASSERT_TRUE(d.acquisition_start);
  EXPECT_EQ(*d.acquisition_start, std::floor(first) + 1e9);  // a whole GPS second at or before the first point
  const auto &x = d.Field("cartesianX"), &y = d.Field("cartesianY"), &z = d.Field("cartesianZ"), &t = d.Field("timeStamp");
  const auto truth = TimesByPoint(scan);
  ASSERT_EQ(d.records, truth.size());
  ASSERT_EQ(t.size(), truth.size());
  ASSERT_EQ(x.size(), truth.size());
  int wrong = 0;
  for (std::size_t r = 0; r < t.size(); ++r) {
    const auto it = truth.find({float(x[r]), float(y[r]), float(z[r])});
    wrong += it == truth.end() || !(std::abs(*d.acquisition_start + t[r] - 1e9 - it->second) < 1e-6);
  }
  EXPECT_EQ(wrong, 0);

  Expected<std::vector<Scan>> back = ReadE57(dir / "t.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  const Scan& got = back->front();
  ASSERT_TRUE(got.HasTime());
  EXPECT_EQ(got.time_base, kAdjustedGpsTime);
  const auto read = TimesByPoint(got);
  ASSERT_EQ(read.size(), truth.size());
  double worst = 0;
  for (const auto& [p, time] : read) {
    ASSERT_TRUE(truth.count(p));
    worst = std::max(worst, std::abs(time - truth.at(p)));
  }
  EXPECT_LT(worst, 1e-6);  // a microsecond: far below a scanner's pulse spacing
}

TEST(E57Time, TimesWithoutADateAreWrittenAsTheyAre) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  const Scan scan = TimedScan(86400.0 * 3 + 0.125, kGpsWeekSeconds);
  ASSERT_TRUE(WriteE57(dir / "w.e57", {scan}, progress, cancel).ok());
  const test::E57BySpecification d = test::DecodeE57BySpecification(ReadBytes(dir / "w.e57"));
  EXPECT_FALSE(d.acquisition_start);
  EXPECT_EQ(d.Field("timeStamp").size(), TimesByPoint(scan).size());  // week seconds name no week: no date to give
  Expected<std::vector<Scan>> back = ReadE57(dir / "w.e57", {}, progress, cancel);
  ASSERT_TRUE(back.ok()) << back.error().ToString();
  EXPECT_EQ(back->front().time_base, kE57ScanSeconds);
  EXPECT_EQ(TimesByPoint(back->front()), TimesByPoint(scan));  // bit for bit
}

TEST(E57Time, ANonFiniteTimeIsRefusedOnWritingAndAnErrorOnReading) {
  TempDir dir;
  NullProgress progress;
  CancelToken cancel;
  Scan scan = TimedScan(100.0, kE57ScanSeconds);
  scan.time[7] = std::numeric_limits<double>::quiet_NaN();
  const Status refused = WriteE57(dir / "nan.e57", {scan}, progress, cancel);
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(Has(refused.error().message, "timed")) << refused.error().message;
  // Another writer's file: the 8th record's timeStamp made NaN behind valid checksums.
  scan.time[7] = 4321.125;
  ASSERT_TRUE(WriteE57(dir / "t.e57", {scan}, progress, cancel).ok());
  std::string logical = LogicalBytes(ReadBytes(dir / "t.e57"));
  char bytes[8];
  std::memcpy(bytes, &scan.time[7], 8);
  const std::size_t at = logical.find(std::string(bytes, 8));
  ASSERT_NE(at, std::string::npos);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(&logical[at], &nan, 8);
  WriteBytes(dir / "nan.e57", PagedBytes(logical));
  Expected<std::vector<Scan>> back = ReadE57(dir / "nan.e57", {}, progress, cancel);
  ASSERT_FALSE(back.ok());
  EXPECT_TRUE(Has(back.error().message, "record 8")) << back.error().message;
  EXPECT_TRUE(Has(back.error().message, "timeStamp")) << back.error().message;
}

}  // namespace
}  // namespace scanreg::io
