#include "core/features/matching.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <Eigen/Core>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/flann.hpp>
#include <string>

#include "core/features/whole_dots.h"

namespace scanreg {

struct MatchIndex::Impl {
  MatchMethod method = MatchMethod::kFlann;
  int flann_checks = 64;
  cv::Mat descriptors;          // N x 128 CV_32F, owned; in memory also Eigen's 128 x N column-major
  std::vector<float> sq_norms;  // kExact: |t|^2 per descriptor
  std::vector<std::int16_t> whole;  // kExact: the descriptors as integers, when WholeDots serves
  std::unique_ptr<cv::flann::Index> flann;
};

namespace {

using ConstDescriptorMap = Eigen::Map<const Eigen::MatrixXf>;  // 128 x n, column = one descriptor

std::vector<float> SquaredNorms(const float* descriptors, int n) {
  std::vector<float> out(static_cast<std::size_t>(n));
  const ConstDescriptorMap m(descriptors, kSiftDescriptorSize, n);
  for (int i = 0; i < n; ++i) out[i] = m.col(i).squaredNorm();
  return out;
}

float ExactDistance(const float* a, const float* b) {
  double sum = 0;
  for (int k = 0; k < kSiftDescriptorSize; ++k) {
    const double d = static_cast<double>(a[k]) - b[k];
    sum += d * d;
  }
  return static_cast<float>(std::sqrt(sum));
}

// Top-2 by squared distance; strict comparisons, so ties keep the lower index (deterministic).
struct Best2 {
  float d1 = std::numeric_limits<float>::infinity();
  float d2 = std::numeric_limits<float>::infinity();
  int i1 = -1;
  int i2 = -1;
  void Add(float d, int i) {
    if (d < d1) {
      d2 = d1;
      i2 = i1;
      d1 = d;
      i1 = i;
    } else if (d < d2) {
      d2 = d;
      i2 = i;
    }
  }
};

// The descriptors as integers when the exact product can be taken in integers on this processor
// (WholeDots), else empty: the float product then serves.
std::vector<std::int16_t> WholeIfFast(const float* descriptors, int n) {
  return WholeDotsAreFast() ? WholeDescriptors(descriptors, n) : std::vector<std::int16_t>{};
}

// Exact two nearest neighbours of each query in train (rows) and, when cols is not null, of each
// train descriptor among the queries, from blocks of the matrix product T^T Q:
// |q - t|^2 = |q|^2 + |t|^2 - 2 q.t. The float product picks the top two; their distances are then
// recomputed directly, so d1 and d2 are exact. When both sides are given as whole numbers, the
// product is taken in integers (WholeDots): the same numbers, since the float one is exact then.
void ExactTwoWay(const float* query, const std::vector<std::int16_t>& query_whole, int nq, const float* train,
                 const std::vector<std::int16_t>& train_whole, int nt, const std::vector<float>& train_norms,
                 std::vector<TwoNearest>* rows, std::vector<TwoNearest>* cols) {
  constexpr int kBlock = 256;  // queries per product: nt x 256 floats (7 MB for 7000 train)
  const bool whole = !query_whole.empty() && !train_whole.empty();
  const std::vector<float> query_norms = SquaredNorms(query, nq);
  const ConstDescriptorMap t(train, kSiftDescriptorSize, nt);
  std::vector<Best2> col_best(cols ? nt : 0);
  rows->assign(nq, TwoNearest{});
  Eigen::MatrixXf dots;
  std::vector<std::int32_t> whole_dots;
  for (int q0 = 0; q0 < nq; q0 += kBlock) {
    const int nb = std::min(kBlock, nq - q0);
    if (whole) {
      whole_dots.resize(static_cast<std::size_t>(nt) * nb);
      WholeDots(train_whole.data(), nt, query_whole.data() + static_cast<std::size_t>(q0) * kSiftDescriptorSize, nb,
                whole_dots.data());
    } else {
      const ConstDescriptorMap qb(query + static_cast<std::size_t>(q0) * kSiftDescriptorSize, kSiftDescriptorSize,
                                  nb);
      dots.noalias() = t.transpose() * qb;  // nt x nb
    }
    for (int k = 0; k < nb; ++k) {
      const float qn = query_norms[q0 + k];
      Best2 best;
      const auto scan_column = [&](const auto* column) {
        for (int j = 0; j < nt; ++j) {
          const float d = qn + train_norms[j] - 2.f * static_cast<float>(column[j]);
          best.Add(d, j);
          if (cols) col_best[j].Add(d, q0 + k);
        }
      };
      if (whole)
        scan_column(whole_dots.data() + static_cast<std::size_t>(k) * nt);
      else
        scan_column(dots.data() + static_cast<std::size_t>(k) * nt);
      if (best.i2 < 0) continue;
      const float* qk = query + static_cast<std::size_t>(q0 + k) * kSiftDescriptorSize;
      TwoNearest& out = (*rows)[q0 + k];
      out = TwoNearest{best.i1, best.i2, ExactDistance(qk, train + static_cast<std::size_t>(best.i1) * kSiftDescriptorSize),
                       ExactDistance(qk, train + static_cast<std::size_t>(best.i2) * kSiftDescriptorSize)};
      if (out.d2 < out.d1) out = TwoNearest{out.second, out.best, out.d2, out.d1};
    }
  }
  if (!cols) return;
  cols->assign(nt, TwoNearest{});
  for (int j = 0; j < nt; ++j) {
    const Best2& best = col_best[j];
    if (best.i2 < 0) continue;
    const float* tj = train + static_cast<std::size_t>(j) * kSiftDescriptorSize;
    TwoNearest& out = (*cols)[j];
    out = TwoNearest{best.i1, best.i2, ExactDistance(tj, query + static_cast<std::size_t>(best.i1) * kSiftDescriptorSize),
                     ExactDistance(tj, query + static_cast<std::size_t>(best.i2) * kSiftDescriptorSize)};
    if (out.d2 < out.d1) out = TwoNearest{out.second, out.best, out.d2, out.d1};
  }
}

// Ratio test (and, with reverse, the mutual-nearest-neighbour check) on nearest-neighbour results.
std::vector<FeatureMatch> RatioFilter(const std::vector<TwoNearest>& nn, double ratio,
                                      const std::vector<TwoNearest>* reverse) {
  std::vector<FeatureMatch> matches;
  for (int i = 0; i < static_cast<int>(nn.size()); ++i) {
    const TwoNearest& n = nn[i];
    // d2 == 0 means two identical train descriptors: ambiguous, rejected.
    if (n.best < 0 || !(n.d2 > 0) || !(n.d1 < ratio * n.d2)) continue;
    if (reverse && (*reverse)[n.best].best != i) continue;
    matches.push_back(FeatureMatch{i, n.best, n.d1});
  }
  return matches;
}

cv::Mat WrapDescriptors(const float* descriptors, int n) {
  // cv::Mat does not write through a const pointer here; the header is only read from.
  return cv::Mat(n, kSiftDescriptorSize, CV_32F, const_cast<float*>(descriptors));
}

}  // namespace

Status MatchOptions::Validate() const {
  auto bad = [](const std::string& what) { return MakeError(ErrorCode::kInvalidArgument, "match options: " + what); };
  if (!(ratio > 0 && ratio <= 1)) return bad("ratio (t_des) must be in (0, 1], got " + std::to_string(ratio));
  if (flann_trees < 1 || flann_trees > 64) return bad("flann_trees must be in [1, 64], got " + std::to_string(flann_trees));
  if (flann_checks < 1) return bad("flann_checks must be >= 1, got " + std::to_string(flann_checks));
  return Status::Ok();
}

MatchIndex::MatchIndex(const ScanFeatures& features, const MatchOptions& options) : impl_(std::make_unique<Impl>()) {
  impl_->method = options.method;
  impl_->flann_checks = options.flann_checks;
  impl_->descriptors = WrapDescriptors(features.descriptors.data(), features.size()).clone();
  if (impl_->method == MatchMethod::kExact) {
    impl_->sq_norms = SquaredNorms(impl_->descriptors.ptr<float>(), impl_->descriptors.rows);
    impl_->whole = WholeIfFast(impl_->descriptors.ptr<float>(), impl_->descriptors.rows);
  }
  if (impl_->method == MatchMethod::kFlann && features.size() >= 2) {
    // FLANN draws its random split dimensions from cv::theRNG(), which is per thread: seeding it
    // here (and restoring it afterwards) makes the forest a function of the seed only.
    cv::RNG& rng = cv::theRNG();
    const cv::RNG saved = rng;
    rng = cv::RNG(options.flann_seed);
    impl_->flann = std::make_unique<cv::flann::Index>(impl_->descriptors, cv::flann::KDTreeIndexParams(options.flann_trees),
                                                      cvflann::FLANN_DIST_L2);
    rng = saved;
  }
}

MatchIndex::~MatchIndex() = default;
MatchIndex::MatchIndex(MatchIndex&&) noexcept = default;
MatchIndex& MatchIndex::operator=(MatchIndex&&) noexcept = default;

int MatchIndex::size() const { return impl_->descriptors.rows; }
MatchMethod MatchIndex::method() const { return impl_->method; }
const float* MatchIndex::Descriptor(int i) const { return impl_->descriptors.ptr<float>(i); }

std::vector<TwoNearest> MatchIndex::Search(const float* descriptors, int n) const {
  std::vector<TwoNearest> out(static_cast<std::size_t>(std::max(n, 0)));
  if (n <= 0 || size() < 2) return out;
  if (impl_->method == MatchMethod::kExact) {
    const std::vector<std::int16_t> query_whole =
        impl_->whole.empty() ? std::vector<std::int16_t>{} : WholeDescriptors(descriptors, n);
    ExactTwoWay(descriptors, query_whole, n, impl_->descriptors.ptr<float>(), impl_->whole, size(), impl_->sq_norms,
                &out, nullptr);
    return out;
  }
  const cv::Mat query = WrapDescriptors(descriptors, n);
  if (impl_->method == MatchMethod::kFlann) {
    cv::Mat indices(n, 2, CV_32S), dists(n, 2, CV_32F);
    // Concurrent searches are safe: FLANN's KD-tree search keeps its state per call and per thread.
    impl_->flann->knnSearch(query, indices, dists, 2, cv::flann::SearchParams(impl_->flann_checks));
    for (int i = 0; i < n; ++i) {
      const int* idx = indices.ptr<int>(i);
      const float* d = dists.ptr<float>(i);  // squared L2
      out[i] = TwoNearest{idx[0], idx[1], std::sqrt(std::max(d[0], 0.f)), std::sqrt(std::max(d[1], 0.f))};
      if (idx[0] < 0 || idx[1] < 0) out[i] = TwoNearest{};
    }
  } else {
    cv::BFMatcher matcher(cv::NORM_L2);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(query, impl_->descriptors, knn, 2);
    for (int i = 0; i < n; ++i) {
      if (knn[i].size() < 2) continue;
      out[i] = TwoNearest{knn[i][0].trainIdx, knn[i][1].trainIdx, knn[i][0].distance, knn[i][1].distance};
    }
  }
  return out;
}

std::vector<FeatureMatch> MatchRatio(const ScanFeatures& query, const MatchIndex& train_index,
                                     const MatchOptions& options, const MatchIndex* query_index) {
  std::vector<FeatureMatch> matches =
      RatioFilter(train_index.Search(query.descriptors.data(), query.size()), options.ratio, nullptr);
  if (!options.cross_check || matches.empty()) return matches;

  std::unique_ptr<MatchIndex> own_index;
  if (query_index == nullptr) {
    own_index = std::make_unique<MatchIndex>(query, options);
    query_index = own_index.get();
  }
  // Search the matched train descriptors back in the query.
  std::vector<float> back(matches.size() * kSiftDescriptorSize);
  for (std::size_t k = 0; k < matches.size(); ++k)
    std::copy_n(train_index.Descriptor(matches[k].train), kSiftDescriptorSize, back.data() + k * kSiftDescriptorSize);
  const std::vector<TwoNearest> reverse = query_index->Search(back.data(), static_cast<int>(matches.size()));
  std::vector<FeatureMatch> mutual;
  mutual.reserve(matches.size());
  for (std::size_t k = 0; k < matches.size(); ++k)
    if (reverse[k].best == matches[k].query) mutual.push_back(matches[k]);
  return mutual;
}

TwoWayMatches MatchRatioBothWays(const MatchIndex& a, const MatchIndex& b, const MatchOptions& options) {
  std::vector<TwoNearest> ab, ba;
  if (a.method() == MatchMethod::kExact && b.method() == MatchMethod::kExact && a.size() >= 2 && b.size() >= 2) {
    ExactTwoWay(a.Descriptor(0), a.impl_->whole, a.size(), b.Descriptor(0), b.impl_->whole, b.size(), b.impl_->sq_norms,
                &ab, &ba);
  } else {
    ab = b.Search(a.size() > 0 ? a.Descriptor(0) : nullptr, a.size());
    ba = a.Search(b.size() > 0 ? b.Descriptor(0) : nullptr, b.size());
  }
  // The reverse results are only complete (usable for the cross-check) when the other side has >= 2.
  const bool cross = options.cross_check;
  TwoWayMatches out;
  out.a_in_b = RatioFilter(ab, options.ratio, cross ? &ba : nullptr);
  out.b_in_a = RatioFilter(ba, options.ratio, cross ? &ab : nullptr);
  return out;
}

std::vector<FeatureMatch> MatchRatio(const ScanFeatures& query, const ScanFeatures& train,
                                     const MatchOptions& options) {
  const MatchIndex train_index(train, options);
  return MatchRatio(query, train_index, options);
}

}  // namespace scanreg
