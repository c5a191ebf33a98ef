#include "core/features/whole_dots.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "core/features/sift.h"
#include "feature_fixtures.h"

namespace scanreg {
namespace {

constexpr int kDims = kSiftDescriptorSize;

// Sparse whole numbers 0..255, as SIFT's descriptors are (most bins small, a few large).
std::vector<float> SiftLike(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(0, 255), keep(0, 3);
  std::vector<float> out(static_cast<std::size_t>(n) * kDims);
  for (float& v : out) v = keep(rng) == 0 ? static_cast<float>(value(rng)) : 0.f;
  return out;
}

// Every size the kernel splits into (blocks of 4 queries x 2 train descriptors, and the rest),
// up to the largest values a descriptor can hold: each sum equals the one taken value by value.
TEST(WholeDots, EqualTheSumsTakenOneByOne) {
  for (const auto& [nq, nt] : {std::pair{1, 1}, {4, 2}, {5, 3}, {7, 9}, {13, 26}}) {
    std::vector<float> q = SiftLike(nq, 7 + nq), t = SiftLike(nt, 11 + nt);
    std::fill_n(q.begin(), kDims, 255.f);  // the largest dot product: 128 x 255^2
    std::fill_n(t.begin(), kDims, 255.f);
    const std::vector<std::int16_t> qw = WholeDescriptors(q.data(), nq), tw = WholeDescriptors(t.data(), nt);
    ASSERT_EQ(qw.size(), q.size());
    ASSERT_EQ(tw.size(), t.size());
    std::vector<std::int32_t> out(static_cast<std::size_t>(nq) * nt, -1);
    WholeDots(tw.data(), nt, qw.data(), nq, out.data());
    for (int k = 0; k < nq; ++k)
      for (int j = 0; j < nt; ++j) {
        std::int64_t sum = 0;
        for (int d = 0; d < kDims; ++d)
          sum += static_cast<std::int64_t>(q[static_cast<std::size_t>(k) * kDims + d]) *
                 static_cast<std::int64_t>(t[static_cast<std::size_t>(j) * kDims + d]);
        EXPECT_EQ(out[static_cast<std::size_t>(k) * nt + j], sum) << nq << "x" << nt << " query " << k << " train " << j;
      }
    EXPECT_EQ(out[0], 128 * 255 * 255);
  }
}

// Only whole numbers in [0, 255] go the integer way; anything else (a fraction, a negative value,
// more than a byte, NaN) leaves the descriptors to the float product.
TEST(WholeDots, AcceptOnlyWholeNumbersOfAByte) {
  std::vector<float> d = SiftLike(3, 5);
  EXPECT_EQ(WholeDescriptors(d.data(), 3).size(), d.size());
  for (const float bad : {0.5f, -1.f, 256.f, std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<float> copy = d;
    copy[200] = bad;
    EXPECT_TRUE(WholeDescriptors(copy.data(), 3).empty()) << bad;
  }
}

// OpenCV's SIFT descriptors of a simulated scan are whole numbers of a byte, so the matcher's
// integer product applies to real detections (the matches themselves are checked against OpenCV's
// brute force in MatchingBenchmark.ExactGemmEqualsBruteForceOnFullSizeStations).
TEST(WholeDots, SiftDescriptorsAreWholeNumbersOfAByte) {
  const auto features = DetectFeatures(test::SmallProject()[0]);
  ASSERT_TRUE(features.ok());
  ASSERT_GT(features->size(), 100);
  EXPECT_EQ(WholeDescriptors(features->descriptors.data(), features->size()).size(), features->descriptors.size());
}

}  // namespace
}  // namespace scanreg
