// The scan store under a memory budget (issue 13, item 1): least recently used scans dropped, read
// again when asked for, scans in use kept alive, read errors passed on, sizes parsed.
#include "core/pipeline/scan_store.h"

#include <gtest/gtest.h>

#include <atomic>

namespace scanreg::pipeline {
namespace {

// A 10 x 20 scan whose points encode its index (so a scan read again is recognisably the same).
Scan Numbered(int index) {
  Scan s("s" + std::to_string(index), 10, 20);
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c) s.Set(r, c, Eigen::Vector3f(float(index), float(r), float(c)), 0.5f);
  return s;
}

struct Counting {
  std::vector<Scan> heads;
  std::shared_ptr<std::atomic<int>> reads = std::make_shared<std::atomic<int>>(0);
  ScanStore::Reader reader() {
    auto count = reads;
    return [count](int i) -> Expected<Scan> {
      ++*count;
      if (i == 4) return MakeError(ErrorCode::kNotFound, "scan file 's4.ptx' is missing");
      return Numbered(i);
    };
  }
  Counting() {
    for (int i = 0; i < 5; ++i) heads.push_back(ScanHead(Numbered(i)));
  }
};

TEST(ScanStore, KeepsTheRecentlyUsedScansWithinItsBudgetAndReadsTheOthersAgain) {
  Counting source;
  const std::size_t one = ScanBytes(Numbered(0));
  ScanStore store(source.heads, source.reader(), 2 * one);  // room for two scans
  for (int i : {0, 1, 2}) {
    Expected<std::shared_ptr<const Scan>> s = store.Get(i);
    ASSERT_TRUE(s.ok());
    EXPECT_EQ((*s)->name, "s" + std::to_string(i));
    EXPECT_EQ((*s)->Point(3, 4), Eigen::Vector3f(float(i), 3.f, 4.f));
  }
  EXPECT_EQ(*source.reads, 3);
  EXPECT_LE(store.peak_bytes(), 2 * one);
  ASSERT_TRUE(store.Get(2).ok());  // resident: not read again
  ASSERT_TRUE(store.Get(1).ok());
  EXPECT_EQ(*source.reads, 3);
  ASSERT_TRUE(store.Get(0).ok());  // dropped (least recently used): read again
  EXPECT_EQ(*source.reads, 4);
  EXPECT_EQ(store.reads(), 4);
  ASSERT_TRUE(store.Get(1).ok());  // 1 was used after 2: still resident, 2 was dropped
  EXPECT_EQ(*source.reads, 4);
  ASSERT_TRUE(store.Get(2).ok());
  EXPECT_EQ(*source.reads, 5);
}

TEST(ScanStore, AScanInUseOutlivesItsEvictionAndErrorsNameTheScan) {
  Counting source;
  ScanStore store(source.heads, source.reader(), 1);  // smaller than one scan: only the last read stays
  Expected<std::shared_ptr<const Scan>> held = store.Get(0);
  ASSERT_TRUE(held.ok());
  for (int i : {1, 2, 3}) ASSERT_TRUE(store.Get(i).ok());
  EXPECT_EQ((*held)->Point(9, 19), Eigen::Vector3f(0.f, 9.f, 19.f));  // still valid while held
  Expected<std::shared_ptr<const Scan>> bad = store.Get(4);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().message.find("s4.ptx"), std::string::npos) << bad.error().message;
  EXPECT_FALSE(store.Get(5).ok());
  EXPECT_FALSE(store.Get(-1).ok());
}

TEST(ScanStore, ScansInMemoryAreNeverRead) {
  std::vector<Scan> scans{Numbered(0), Numbered(1)};
  ScanStore store(scans);
  Expected<std::shared_ptr<const Scan>> s = store.Get(1);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->get(), &scans[1]);
  EXPECT_EQ(store.reads(), 0);
  EXPECT_EQ(store.heads()[1].name, "s1");
  EXPECT_TRUE(store.heads()[1].points.empty());
}

// A surface whose samples encode the scan (a 30 x 30 plane at height `index`).
std::shared_ptr<const IcpSurface> Plane(int index) {
  std::vector<Eigen::Vector3d> pts;
  for (int x = 0; x < 30; ++x)
    for (int y = 0; y < 30; ++y) pts.emplace_back(0.1 * x, 0.1 * y, double(index));
  return std::make_shared<const IcpSurface>(pts, DenseIcpOptions());
}

TEST(ScanStore, SurfacesShareTheBudgetWithTheScans) {
  Counting source;
  const std::size_t scan = ScanBytes(Numbered(0)), surface = Plane(0)->Bytes();
  ASSERT_GT(surface, 900 * 2 * sizeof(Eigen::Vector3d));  // points and normals at least
  ScanStore store(source.heads, source.reader(), scan + surface);  // room for one scan and one surface
  int builds = 0;
  const auto surface_of = [&](int i) {
    return store.Surface(i, [&, i] {
      ++builds;
      return Plane(i);
    });
  };
  std::shared_ptr<const IcpSurface> s0 = surface_of(0);
  ASSERT_TRUE(s0);
  EXPECT_DOUBLE_EQ(s0->points.front().z(), 0.0);
  EXPECT_EQ(surface_of(0), s0);  // resident: the same, not built again
  EXPECT_EQ(builds, 1);
  ASSERT_TRUE(store.Get(1).ok());
  EXPECT_EQ(surface_of(0), s0);  // one scan and one surface fit
  EXPECT_EQ(builds, 1);
  ASSERT_TRUE(store.Get(2).ok());  // a second scan: the least recently used (scan 1) goes
  EXPECT_EQ(*source.reads, 2);
  EXPECT_LE(store.peak_bytes(), scan + surface);
  std::shared_ptr<const IcpSurface> s3 = surface_of(3);  // a second surface: surface 0 goes (scan 2 is newer)
  EXPECT_DOUBLE_EQ(s3->points.front().z(), 3.0);
  EXPECT_EQ(builds, 2);
  s0.reset();
  std::shared_ptr<const IcpSurface> again = surface_of(0);
  EXPECT_EQ(builds, 3);
  EXPECT_DOUBLE_EQ(again->points.front().z(), 0.0);
  EXPECT_EQ(store.surface_builds(), 3);
  EXPECT_EQ(store.reads(), 2);
  EXPECT_LE(store.peak_bytes(), scan + surface);
}

TEST(ScanStore, MemoryBudgetsAreParsedWithTheirUnits) {
  EXPECT_EQ(*ParseMemoryBudget("6G"), std::size_t(6) << 30);
  EXPECT_EQ(*ParseMemoryBudget("800M"), std::size_t(800) << 20);
  EXPECT_EQ(*ParseMemoryBudget("1.5G"), std::size_t(3) << 29);
  EXPECT_EQ(*ParseMemoryBudget("2"), std::size_t(2) << 30);
  for (const char* bad : {"", "lots", "-1G", "10K", "0.5M", "6Q", "nanG", "1e30G"}) {
    Expected<std::size_t> r = ParseMemoryBudget(bad);
    EXPECT_FALSE(r.ok()) << bad;
    if (!r.ok()) {
      EXPECT_NE(r.error().message.find("6G"), std::string::npos);
    }
  }
  EXPECT_GE(DefaultMemoryBudget(), std::size_t(1) << 30);
}

}  // namespace
}  // namespace scanreg::pipeline
