// A time per point in E57 (issue 34): written as the timeStamp field, counted from the scan's
// acquisitionStart (ASTM E2807 §8.4.3) when the times are GPS times, and read back in the base they
// came in. The file is checked by decoding it as the standard lays it out (pages, XML, the points
// section's packets), not only with our reader.
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

// What the standard says the file holds for one scan whose prototype has only Float fields.
struct Decoded {
  bool has_start = false;
  double start = 0;                            // acquisitionStart/dateTimeValue
  std::vector<std::vector<double>> records;    // one value per prototype field
  std::vector<std::string> fields;
  int Field(const std::string& name) const {
    for (std::size_t i = 0; i < fields.size(); ++i)
      if (fields[i] == name) return static_cast<int>(i);
    return -1;
  }
};

// Decodes pages (1020 data bytes + CRC each), the XML section (offset and length at bytes 24 and
// 32 of the header), and the CompressedVector's data packets: 1 type byte, 1 flag byte, length - 1
// (2 bytes), bytestream count (2), each bytestream's length (2), then the bytestreams.
Decoded DecodeBySpecification(const std::string& file) {
  Decoded out;
  const std::string logical = LogicalBytes(file);
  const auto to_logical = [](std::uint64_t physical) { return physical / 1024 * 1020 + physical % 1024; };
  std::uint64_t xml_offset = 0, xml_length = 0;
  std::memcpy(&xml_offset, &logical[24], 8);
  std::memcpy(&xml_length, &logical[32], 8);
  pugi::xml_document doc;
  EXPECT_TRUE(doc.load_string(logical.substr(to_logical(xml_offset), xml_length).c_str()));
  const pugi::xml_node scan = doc.child("e57Root").child("data3D").first_child();
  if (const pugi::xml_node start = scan.child("acquisitionStart").child("dateTimeValue")) {
    out.has_start = true;
    out.start = std::stod(start.text().get());
  }
  const pugi::xml_node points = scan.child("points");
  std::vector<int> bytes;
  for (pugi::xml_node f = points.child("prototype").first_child(); f; f = f.next_sibling()) {
    EXPECT_STREQ(f.attribute("type").value(), "Float") << f.name();
    out.fields.push_back(f.name());
    bytes.push_back(std::string(f.attribute("precision").value()) == "single" ? 4 : 8);
  }
  const std::uint64_t count = std::stoull(points.attribute("recordCount").value());
  const std::uint64_t section = to_logical(std::stoull(points.attribute("fileOffset").value()));
  std::uint64_t data = 0;
  std::memcpy(&data, &logical[section + 16], 8);
  std::uint64_t at = to_logical(data);
  std::vector<std::vector<double>> columns(bytes.size());
  while (columns[0].size() < count && at + 6 <= logical.size()) {
    EXPECT_EQ(logical[at], 1) << "a data packet";
    std::uint16_t length = 0, streams = 0;
    std::memcpy(&length, &logical[at + 2], 2);
    std::memcpy(&streams, &logical[at + 4], 2);
    EXPECT_EQ(streams, bytes.size());
    std::uint64_t pos = at + 6 + 2 * streams;
    for (std::size_t s = 0; s < streams; ++s) {
      std::uint16_t n = 0;
      std::memcpy(&n, &logical[at + 6 + 2 * s], 2);
      for (std::uint64_t k = 0; k < n; k += bytes[s]) {
        if (bytes[s] == 4) {
          float v;
          std::memcpy(&v, &logical[pos + k], 4);
          columns[s].push_back(v);
        } else {
          double v;
          std::memcpy(&v, &logical[pos + k], 8);
          columns[s].push_back(v);
        }
      }
      pos += n;
    }
    at += std::uint64_t(length) + 1;
  }
  for (std::uint64_t r = 0; r < count && r < columns[0].size(); ++r) {
    std::vector<double> record;
    for (const auto& c : columns) record.push_back(r < c.size() ? c[r] : NAN);
    out.records.push_back(record);
  }
  return out;
}

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

  const Decoded d = DecodeBySpecification(ReadBytes(dir / "t.e57"));
  ASSERT_TRUE(d.has_start);
  EXPECT_EQ(d.start, std::floor(first) + 1e9);  // a whole GPS second at or before the first point
  const int x = d.Field("cartesianX"), y = d.Field("cartesianY"), z = d.Field("cartesianZ"), t = d.Field("timeStamp");
  ASSERT_GE(t, 0);
  const auto truth = TimesByPoint(scan);
  ASSERT_EQ(d.records.size(), truth.size());
  int wrong = 0;
  for (const auto& r : d.records) {
    const auto it = truth.find({float(r[x]), float(r[y]), float(r[z])});
    wrong += it == truth.end() || !(std::abs(d.start + r[t] - 1e9 - it->second) < 1e-6);
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
  const Decoded d = DecodeBySpecification(ReadBytes(dir / "w.e57"));
  EXPECT_FALSE(d.has_start);  // week seconds name no week: no date to give
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
