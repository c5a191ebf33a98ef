#include "core/features/feature_cache.h"

#include <gtest/gtest.h>

#include <fstream>

#include "core/common/log.h"
#include "feature_fixtures.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

const Scan& SmallScan() {
  static const Scan scan = test::MakeProject(1, 600, 150).at(0);
  return scan;
}

void ExpectSame(const ScanFeatures& a, const ScanFeatures& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.rows, b.rows);
  EXPECT_EQ(a.cols, b.cols);
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].u, b.keypoints[i].u);
    EXPECT_EQ(a.keypoints[i].v, b.keypoints[i].v);
    EXPECT_EQ(a.keypoints[i].size, b.keypoints[i].size);
    EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
    EXPECT_EQ(a.keypoints[i].response, b.keypoints[i].response);
  }
  EXPECT_EQ(a.descriptors, b.descriptors);
}

// Captures warnings for the duration of a test.
class WarningCounter {
 public:
  WarningCounter() {
    SetLogHandler([this](LogLevel level, const std::string&) { warnings += level == LogLevel::kWarning; });
  }
  ~WarningCounter() { SetLogHandler({}); }
  int warnings = 0;
};

TEST(FeatureCacheTest, SecondCallHitsTheCacheWithIdenticalFeatures) {
  test::TempDir dir;
  const auto cache_dir = dir / "project.scanreg-cache" / "features";  // created on demand
  bool from_cache = true;
  const auto first = LoadOrDetectFeatures(SmallScan(), SiftOptions(), cache_dir, &from_cache);
  ASSERT_TRUE(first.ok()) << first.error().ToString();
  EXPECT_FALSE(from_cache);
  ASSERT_GT(first->size(), 50);
  EXPECT_TRUE(std::filesystem::exists(FeatureCachePath(SmallScan(), SiftOptions(), cache_dir)));
  const auto second = LoadOrDetectFeatures(SmallScan(), SiftOptions(), cache_dir, &from_cache);
  ASSERT_TRUE(second.ok());
  EXPECT_TRUE(from_cache);
  ExpectSame(*first, *second);
  const auto direct = DetectFeatures(SmallScan());
  ASSERT_TRUE(direct.ok());
  ExpectSame(*first, *direct);
  // Only the entry remains: no temporary files left behind.
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(cache_dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(FeatureCacheTest, CorruptOrTruncatedEntryIsDetectedAndRedetected) {
  test::TempDir dir;
  const auto path = FeatureCachePath(SmallScan(), SiftOptions(), dir.path());
  const auto reference = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path());
  ASSERT_TRUE(reference.ok());
  const auto size = std::filesystem::file_size(path);

  WarningCounter log;
  {  // flip one byte in the middle of the descriptors
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    f.put('\x5a');
  }
  bool from_cache = true;
  auto again = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache);
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(from_cache);
  EXPECT_EQ(log.warnings, 1);
  ExpectSame(*reference, *again);
  // Rewritten: the next call hits.
  again = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache);
  EXPECT_TRUE(from_cache);

  std::filesystem::resize_file(path, size - 100);  // truncated
  again = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache);
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(from_cache);
  EXPECT_EQ(log.warnings, 2);
  ExpectSame(*reference, *again);

  { std::ofstream(path, std::ios::binary | std::ios::trunc) << "garbage"; }
  again = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache);
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(from_cache);
  EXPECT_EQ(log.warnings, 3);
  EXPECT_EQ(std::filesystem::file_size(path), size);
}

TEST(FeatureCacheTest, ChangedOptionsOrScanUseAnotherEntry) {
  test::TempDir dir;
  SiftOptions other;
  other.contrast_threshold = 0.06;
  EXPECT_NE(FeatureCachePath(SmallScan(), SiftOptions(), dir.path()), FeatureCachePath(SmallScan(), other, dir.path()));
  bool from_cache = true;
  ASSERT_TRUE(LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache).ok());
  const auto b = LoadOrDetectFeatures(SmallScan(), other, dir.path(), &from_cache);
  ASSERT_TRUE(b.ok());
  EXPECT_FALSE(from_cache);
  const auto a = LoadOrDetectFeatures(SmallScan(), SiftOptions(), dir.path(), &from_cache);
  EXPECT_TRUE(from_cache);
  EXPECT_LT(b->size(), a->size());  // a higher contrast threshold keeps fewer keypoints

  Scan changed = SmallScan();
  EXPECT_EQ(ScanContentHash(changed), ScanContentHash(SmallScan()));
  changed.name = "renamed";  // the name is not content
  EXPECT_EQ(ScanContentHash(changed), ScanContentHash(SmallScan()));
  changed.reflectance[12345] += 0.01f;
  EXPECT_NE(ScanContentHash(changed), ScanContentHash(SmallScan()));
  EXPECT_NE(FeatureCachePath(changed, SiftOptions(), dir.path()), FeatureCachePath(SmallScan(), SiftOptions(), dir.path()));
}

TEST(FeatureCacheTest, BadOptionsAreAnErrorNotACacheMiss) {
  test::TempDir dir;
  SiftOptions bad;
  bad.sigma = 0;
  const auto r = LoadOrDetectFeatures(SmallScan(), bad, dir.path());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, ErrorCode::kInvalidArgument);
}

}  // namespace
}  // namespace scanreg
