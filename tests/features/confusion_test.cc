#include "core/features/confusion.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <atomic>
#include <cstdio>
#include <iostream>

#include "feature_fixtures.h"

namespace scanreg {
namespace {

const std::vector<ScanFeatures>& SmallProjectFeatures() {
  static const std::vector<ScanFeatures> features = [] {
    std::vector<ScanFeatures> out;
    for (const Scan& scan : test::SmallProject()) {
      auto f = DetectFeatures(scan);
      EXPECT_TRUE(f.ok());
      out.push_back(f.ok() ? std::move(*f) : ScanFeatures());
    }
    return out;
  }();
  return features;
}

class CountingProgress final : public ProgressSink {
 public:
  void Report(double fraction, const std::string&) override {
    ++calls;
    double prev = last.load();
    while (fraction > prev && !last.compare_exchange_weak(prev, fraction)) {
    }
  }
  std::atomic<int> calls{0};
  std::atomic<double> last{0};
};

TEST(ConfusionTest, SimulatedProjectHasTheExpectedStructure) {
  const auto& features = SmallProjectFeatures();
  ASSERT_EQ(features.size(), 4u);
  CountingProgress progress;
  CancelToken cancel;
  const auto table = MatchAllPairs(features, MatchOptions(), progress, cancel);
  ASSERT_TRUE(table.ok()) << table.error().ToString();
  const Eigen::MatrixXi& c = table->confusion;
  std::cout << "confusion matrix (4 stations, 1200 x 300):\n" << c << "\n";
  ASSERT_EQ(c.rows(), 4);
  ASSERT_EQ(c.cols(), 4);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(c(i, i), features[i].size());
  EXPECT_NE(c, c.transpose());  // the ratio test is not symmetric
  // Neighbouring stations (5 m) share more distinctive features than far ones (15 m).
  EXPECT_GT(c(0, 1), c(0, 3));
  EXPECT_GT(c(3, 2), c(3, 0));
  EXPECT_GT(c(0, 1), 20);
  // Every ordered pair is there, and Find agrees with C.
  ASSERT_EQ(table->pairs.size(), 12u);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      const PairMatches* pm = table->Find(i, j);
      if (i == j) {
        EXPECT_EQ(pm, nullptr);
        continue;
      }
      ASSERT_NE(pm, nullptr);
      EXPECT_EQ(pm->query_scan, i);
      EXPECT_EQ(pm->train_scan, j);
      EXPECT_EQ(static_cast<int>(pm->matches.size()), c(i, j));
      for (const auto& m : pm->matches) {
        ASSERT_GE(m.query, 0);
        ASSERT_LT(m.query, features[i].size());
        ASSERT_GE(m.train, 0);
        ASSERT_LT(m.train, features[j].size());
      }
    }
  EXPECT_EQ(table->Find(0, 4), nullptr);
  EXPECT_EQ(table->Find(-1, 0), nullptr);
  EXPECT_GT(progress.calls.load(), 0);
  EXPECT_LE(progress.calls.load(), 210);
  EXPECT_DOUBLE_EQ(progress.last.load(), 1.0);
}

class ThreadCountTest : public ::testing::TestWithParam<MatchMethod> {};

TEST_P(ThreadCountTest, SameResultForOneAndTwoThreads) {
  const auto& features = SmallProjectFeatures();
  NullProgress progress;
  CancelToken cancel;
  MatchOptions options;
  options.method = GetParam();
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto one = MatchAllPairs(features, options, progress, cancel);
  omp_set_num_threads(2);
  const auto two = MatchAllPairs(features, options, progress, cancel);
  omp_set_num_threads(saved);
  ASSERT_TRUE(one.ok() && two.ok());
  EXPECT_EQ(one->confusion, two->confusion);
  for (std::size_t p = 0; p < one->pairs.size(); ++p) {
    ASSERT_EQ(one->pairs[p].matches.size(), two->pairs[p].matches.size());
    for (std::size_t k = 0; k < one->pairs[p].matches.size(); ++k) {
      EXPECT_EQ(one->pairs[p].matches[k].query, two->pairs[p].matches[k].query);
      EXPECT_EQ(one->pairs[p].matches[k].train, two->pairs[p].matches[k].train);
      EXPECT_EQ(one->pairs[p].matches[k].distance, two->pairs[p].matches[k].distance);
    }
  }
  const auto matrix = ConfusionMatrix(features, options, progress, cancel);
  ASSERT_TRUE(matrix.ok());
  EXPECT_EQ(*matrix, one->confusion);
}

INSTANTIATE_TEST_SUITE_P(Methods, ThreadCountTest, ::testing::Values(MatchMethod::kExact, MatchMethod::kFlann));

// The matches are real: both keypoints of a match between neighbouring stations see the same
// world point (reference poses) far more often than chance (~0). At 1200 x 300 the repeated
// window grids and textures of the simulated street make up most of the rest.
TEST(ConfusionTest, NeighbourMatchesJoinTheSameWorldPoints) {
  const auto& scans = test::SmallProject();
  const auto& features = SmallProjectFeatures();
  NullProgress progress;
  CancelToken cancel;
  const auto table = MatchAllPairs(features, MatchOptions(), progress, cancel);
  ASSERT_TRUE(table.ok());
  for (auto [i, j] : {std::pair{0, 1}, std::pair{1, 0}, std::pair{2, 3}}) {
    int close = 0, with_points = 0;
    for (const auto& m : table->Find(i, j)->matches) {
      Eigen::Vector3d pi = Eigen::Vector3d::Zero(), pj = Eigen::Vector3d::Zero();
      const Keypoint& ki = features[i].keypoints[m.query];
      const Keypoint& kj = features[j].keypoints[m.train];
      if (!test::WorldPointNear(scans[i], ki.u, ki.v, &pi) || !test::WorldPointNear(scans[j], kj.u, kj.v, &pj))
        continue;
      ++with_points;
      close += (pi - pj).norm() < 0.3;
    }
    std::printf("C(%d,%d): %d matches with 3D points, %d within 0.3 m\n", i, j, with_points, close);
    EXPECT_GE(with_points, 20);
    EXPECT_GE(close, 10);
    EXPECT_GE(close, 0.25 * with_points);
  }
}

TEST(ConfusionTest, CancelledAndBadInputAreReported) {
  const auto& features = SmallProjectFeatures();
  NullProgress progress;
  CancelToken cancel;
  cancel.Cancel();
  const auto cancelled = MatchAllPairs(features, MatchOptions(), progress, cancel);
  ASSERT_FALSE(cancelled.ok());
  EXPECT_EQ(cancelled.error().code, ErrorCode::kCancelled);

  CancelToken go;
  MatchOptions bad;
  bad.ratio = -1;
  EXPECT_EQ(MatchAllPairs(features, bad, progress, go).error().code, ErrorCode::kInvalidArgument);
  std::vector<ScanFeatures> broken = {features[0], features[1]};
  broken[1].descriptors.pop_back();
  EXPECT_EQ(MatchAllPairs(broken, MatchOptions(), progress, go).error().code, ErrorCode::kInvalidArgument);

  const auto one = MatchAllPairs({features[0]}, MatchOptions(), progress, go);
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one->confusion(0, 0), features[0].size());
  EXPECT_TRUE(one->pairs.empty());
}

TEST(ConfusionTest, ChosenPairsMatchAsInTheFullTableAndTheOthersAreSkipped) {
  const auto& features = SmallProjectFeatures();
  ASSERT_GE(features.size(), 3u);
  NullProgress progress;
  CancelToken go;
  const auto all = MatchAllPairs(features, MatchOptions(), progress, go);
  ASSERT_TRUE(all.ok());
  const int n = static_cast<int>(features.size());
  const auto some = MatchPairs(features, {{1, 0}, {0, 1}, {1, 2}}, MatchOptions(), progress, go);
  ASSERT_TRUE(some.ok());
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const bool chosen = i == j || (std::min(i, j) == 0 && std::max(i, j) == 1) || (std::min(i, j) == 1 && std::max(i, j) == 2);
      if (chosen) {
        EXPECT_EQ(some->confusion(i, j), all->confusion(i, j)) << i << "," << j;
      } else {
        EXPECT_EQ(some->confusion(i, j), kSkippedPair) << i << "," << j;
        ASSERT_NE(some->Find(i, j), nullptr);
        EXPECT_TRUE(some->Find(i, j)->matches.empty());
      }
    }
  EXPECT_GT(some->confusion(0, 1), 0) << "neighbouring stations share features";
  const auto bad = MatchPairs(features, {{0, n}}, MatchOptions(), progress, go);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, ErrorCode::kInvalidArgument);
  EXPECT_NE(bad.error().message.find("not a pair"), std::string::npos) << bad.error().message;
}

}  // namespace
}  // namespace scanreg
