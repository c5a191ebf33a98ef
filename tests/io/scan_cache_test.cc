// The binary scan cache (issue 13, item 2): a second read of a scan file comes from the cache with
// the same scans; a corrupt entry is rebuilt with a warning; a changed source file is re-read.
#include "core/io/scan_cache.h"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>

#include "core/io/ptx.h"
#include "core/io/scan_file.h"
#include "tests/support/test_paths.h"

namespace scanreg::io {
namespace {

Scan Grid(const std::string& name, float offset) {
  Scan scan(name, 12, 30);
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c)
      if ((r + c) % 4 != 0) scan.Set(r, c, Eigen::Vector3f(4.0f + offset, 0.05f * c, 0.1f * r - 0.3f), 0.01f * c);
  scan.world_from_scan.translation() = Eigen::Vector3d(512345.678, 5401234.5, 100.25);
  return scan;
}

void ExpectSameScans(const std::vector<Scan>& a, const std::vector<Scan>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].name, b[k].name);
    ASSERT_EQ(a[k].rows, b[k].rows);
    ASSERT_EQ(a[k].cols, b[k].cols);
    EXPECT_EQ(a[k].valid, b[k].valid);
    EXPECT_EQ(a[k].reflectance, b[k].reflectance);
    for (std::size_t i = 0; i < a[k].size(); ++i) ASSERT_EQ(a[k].points[i], b[k].points[i]) << "cell " << i;
    EXPECT_EQ(a[k].world_from_scan.matrix(), b[k].world_from_scan.matrix()) << "bit for bit at UTM coordinates";
    EXPECT_EQ(a[k].angles.azimuth, b[k].angles.azimuth);
    EXPECT_EQ(a[k].angles.elevation, b[k].angles.elevation);
    EXPECT_EQ(a[k].list_points, b[k].list_points);
    EXPECT_EQ(a[k].list_reflectance, b[k].list_reflectance);
    EXPECT_EQ(a[k].single_viewpoint, b[k].single_viewpoint);
    EXPECT_EQ(a[k].grid_from_file, b[k].grid_from_file);
    EXPECT_EQ(a[k].sensor, b[k].sensor);
    EXPECT_EQ(a[k].list_sensor, b[k].list_sensor);
  }
}

struct CacheFixture : ::testing::Test {
  test::TempDir dir;
  std::filesystem::path ptx = dir / "two.ptx", cache = dir / ".scanreg-cache";
  NullProgress progress;
  CancelToken cancel;
  void Write(float offset) {
    ASSERT_TRUE(WritePtx(ptx, {Grid("a", offset), Grid("b", offset + 1)}, progress, cancel).ok());
  }
  std::vector<Scan> Read(bool* from_cache) {
    auto scans = ReadScanFileCached(ptx, cache, progress, cancel, from_cache);
    EXPECT_TRUE(scans.ok()) << scans.error().message;
    return scans.ok() ? *scans : std::vector<Scan>{};
  }
};

TEST_F(CacheFixture, ASecondReadComesFromTheCacheUnchanged) {
  Write(0);
  bool hit = true;
  const std::vector<Scan> parsed = Read(&hit);
  EXPECT_FALSE(hit);
  auto key = SourceFileKey(ptx);
  ASSERT_TRUE(key.ok());
  EXPECT_TRUE(std::filesystem::is_regular_file(ScanCachePath(cache, ptx, *key)));
  const std::vector<Scan> cached = Read(&hit);
  EXPECT_TRUE(hit);
  ExpectSameScans(parsed, cached);
  auto direct = ReadScanFile(ptx, progress, cancel);
  ASSERT_TRUE(direct.ok());
  ExpectSameScans(*direct, cached);
}

// A scan's points off its grid and its viewpoint flag come back from the cache as they went in;
// an entry cut inside the list is refused, not read short.
TEST(ScanCache, KeepsTheListedPointsAndTheViewpoint) {
  Scan with_list = Grid("merged", 0);
  for (int k = 0; k < 500; ++k) {
    with_list.list_points.emplace_back(6.0f + 0.01f * k, -0.02f * k, 1.5f);
    with_list.list_reflectance.push_back(0.001f * k);
  }
  with_list.single_viewpoint = false;
  with_list.grid_from_file = false;
  with_list.AddSensor();  // each point's sensor position (a mobile mapper's)
  for (std::size_t i = 0; i < with_list.size(); ++i) with_list.sensor[i] = Eigen::Vector3f(0.1f * float(i % 13), 2, 1);
  for (std::size_t k = 0; k < with_list.list_sensor.size(); ++k) with_list.list_sensor[k] = Eigen::Vector3f(-3, 0.5f * float(k), 1);
  const std::string bytes = SerializeScanCache({with_list, Grid("plain", 1)}, 77);
  Expected<std::vector<Scan>> back = ParseScanCache(bytes, 77);
  ASSERT_TRUE(back.ok()) << back.error().message;
  ExpectSameScans({with_list, Grid("plain", 1)}, *back);
  EXPECT_EQ(back->front().CountPoints(), with_list.CountValid() + 500);
  std::string cut = SerializeScanCache({with_list}, 77);
  cut.resize(cut.size() - 3000);
  EXPECT_FALSE(ParseScanCache(cut, 77).ok());
}

TEST_F(CacheFixture, ACorruptEntryIsRebuilt) {
  Write(0);
  bool hit = true;
  const std::vector<Scan> parsed = Read(&hit);
  const std::filesystem::path entry = ScanCachePath(cache, ptx, SourceFileKey(ptx).value());
  {
    std::fstream f(entry, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(entry) / 2));
    f.put('\x5a');
  }
  const std::vector<Scan> again = Read(&hit);
  EXPECT_FALSE(hit) << "a corrupt entry is not used";
  ExpectSameScans(parsed, again);
  Read(&hit);
  EXPECT_TRUE(hit) << "and it was written anew";
  // Truncated and foreign entries are refused with a reason.
  std::ifstream in(entry, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_FALSE(ParseScanCache(bytes.substr(0, bytes.size() / 3), SourceFileKey(ptx).value()).ok());
  auto foreign = ParseScanCache(bytes, 12345);
  ASSERT_FALSE(foreign.ok());
  EXPECT_NE(foreign.error().message.find("another file"), std::string::npos);
}

// One scan of a multi-scan file is read alone from the cache (its header and record, each checked):
// the same scan, the others left empty; damage to another scan's record does not touch it, while a
// whole read notices the damage and rebuilds the entry from the source.
TEST_F(CacheFixture, OneScanOfAFileIsReadAloneAndChecked) {
  Write(0);
  bool hit = true;
  const std::vector<Scan> all = Read(&hit);
  ASSERT_EQ(all.size(), 2u);
  auto second = ReadScanFileCached(ptx, cache, progress, cancel, &hit, 1);
  ASSERT_TRUE(second.ok()) << second.error().message;
  EXPECT_TRUE(hit);
  ASSERT_EQ(second->size(), 2u);
  EXPECT_EQ((*second)[0].size(), 0u) << "the other scan is not read";
  ExpectSameScans({all[1]}, {(*second)[1]});
  // Beyond the file's scans: its scans, all empty (the caller names the missing one).
  auto beyond = ReadScanFileCached(ptx, cache, progress, cancel, &hit, 5);
  ASSERT_TRUE(beyond.ok());
  EXPECT_EQ(beyond->size(), 2u);
  // Damage inside the first scan's record (its points start well after the header).
  const std::filesystem::path entry = ScanCachePath(cache, ptx, SourceFileKey(ptx).value());
  {
    std::fstream f(entry, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(700);
    f.put('\x5a');
  }
  auto still = ReadScanFileCached(ptx, cache, progress, cancel, &hit, 1);
  ASSERT_TRUE(still.ok());
  EXPECT_TRUE(hit) << "the second scan's record is intact";
  ExpectSameScans({all[1]}, {(*still)[1]});
  auto first = ReadScanFileCached(ptx, cache, progress, cancel, &hit, 0);
  ASSERT_TRUE(first.ok());
  EXPECT_FALSE(hit) << "the damaged record is refused and the source read again";
  ExpectSameScans({all[0]}, {(*first)[0]});
  EXPECT_EQ((*first)[1].size(), all[1].size()) << "read from the source: every scan";
  Read(&hit);
  EXPECT_TRUE(hit) << "and the entry was written anew";
}

TEST_F(CacheFixture, AChangedSourceFileIsReadAgain) {
  Write(0);
  bool hit = true;
  Read(&hit);
  const std::filesystem::path old_entry = ScanCachePath(cache, ptx, SourceFileKey(ptx).value());
  Write(0.5f);  // the same file name, other points
  const std::vector<Scan> changed = Read(&hit);
  EXPECT_FALSE(hit);
  ASSERT_EQ(changed.size(), 2u);
  EXPECT_FLOAT_EQ(changed[0].Point(0, 1).x(), 4.5f);
  EXPECT_FALSE(std::filesystem::exists(old_entry)) << "the superseded entry is removed: one entry per file";
  EXPECT_TRUE(std::filesystem::exists(ScanCachePath(cache, ptx, SourceFileKey(ptx).value())));
}

// Reopening a project does not hash every source file again: the key is memoised by the file's
// size and time, and a changed file is hashed again.
TEST_F(CacheFixture, ASourceKeyIsMemoisedUntilTheFileChanges) {
  const auto memo_lines = [&] {
    std::ifstream in(cache / "source-keys");
    int n = 0;
    for (std::string line; std::getline(in, line);) n += line.find(ptx.filename().string()) != std::string::npos;
    return n;
  };
  const auto now = std::filesystem::file_time_type::clock::now();
  Write(0);
  std::filesystem::last_write_time(ptx, now - std::chrono::hours(1));
  const Expected<std::uint64_t> first = MemoisedSourceFileKey(ptx, cache);
  ASSERT_TRUE(first.ok());
  EXPECT_EQ(*first, SourceFileKey(ptx).value());
  EXPECT_EQ(memo_lines(), 1);
  EXPECT_EQ(MemoisedSourceFileKey(ptx, cache).value(), *first);  // from the memo
  EXPECT_EQ(memo_lines(), 1);

  Write(0.5f);  // other points, another time
  std::filesystem::last_write_time(ptx, now - std::chrono::minutes(30));
  const Expected<std::uint64_t> second = MemoisedSourceFileKey(ptx, cache);
  ASSERT_TRUE(second.ok());
  EXPECT_NE(*second, *first);
  EXPECT_EQ(*second, SourceFileKey(ptx).value());
  EXPECT_EQ(memo_lines(), 2);

  Write(1.0f);  // just written: hashed, not memoised (its time may not yet tell a later write)
  EXPECT_EQ(MemoisedSourceFileKey(ptx, cache).value(), SourceFileKey(ptx).value());
  EXPECT_EQ(memo_lines(), 2);
}

}  // namespace
}  // namespace scanreg::io
