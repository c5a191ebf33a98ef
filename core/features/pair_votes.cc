#include "core/features/pair_votes.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>

namespace scanreg {
namespace {

// Indices 0..rows-1 thinned evenly to at most `cap`, in order.
std::vector<int> Thin(int rows, int cap) {
  std::vector<int> out;
  const int take = std::min(rows, cap);
  for (int k = 0; k < take; ++k) out.push_back(static_cast<int>(static_cast<long>(k) * rows / take));
  return out;
}

}  // namespace

Eigen::MatrixXi PairVotes(const std::vector<DescriptorSet>& sets, int dim, const PairVoteOptions& options) {
  const int n = static_cast<int>(sets.size());
  Eigen::MatrixXi votes = Eigen::MatrixXi::Zero(n, n);
  // The indexed rows of every scan in one matrix, with the scan each came from.
  std::vector<int> owner;
  cv::Mat indexed;
  for (int i = 0; i < n; ++i) {
    if (sets[i].rows < 2) continue;
    for (int r : Thin(sets[i].rows, options.max_indexed)) {
      indexed.push_back(cv::Mat(1, dim, CV_32F, const_cast<float*>(sets[i].data + static_cast<std::size_t>(r) * dim)));
      owner.push_back(i);
    }
  }
  const int k = std::min<int>(options.neighbours, static_cast<int>(owner.size()));
  if (k < 2) return votes;
  // FLANN draws its split dimensions from cv::theRNG() (per thread): seeded here, restored after.
  cv::RNG& rng = cv::theRNG();
  const cv::RNG saved = rng;
  rng = cv::RNG(options.seed);
  cv::flann::Index forest(indexed, cv::flann::KDTreeIndexParams(4), cvflann::FLANN_DIST_L2);
  rng = saved;
  const float ratio2 = static_cast<float>(options.ratio * options.ratio);  // FLANN returns squared distances
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < n; ++i) {
    if (sets[i].rows < 2) continue;
    const std::vector<int> rows = Thin(sets[i].rows, options.max_queries);
    cv::Mat query(static_cast<int>(rows.size()), dim, CV_32F);
    for (std::size_t q = 0; q < rows.size(); ++q)
      std::copy_n(sets[i].data + static_cast<std::size_t>(rows[q]) * dim, dim, query.ptr<float>(static_cast<int>(q)));
    cv::Mat indices(query.rows, k, CV_32S), dists(query.rows, k, CV_32F);
    forest.knnSearch(query, indices, dists, k, cv::flann::SearchParams(options.checks));
    std::vector<float> first(n), second(n);
    for (int q = 0; q < query.rows; ++q) {
      const int* idx = indices.ptr<int>(q);
      const float* d = dists.ptr<float>(q);
      std::fill(first.begin(), first.end(), -1.0f);
      std::fill(second.begin(), second.end(), -1.0f);
      for (int m = 0; m < k; ++m) {
        if (idx[m] < 0) continue;
        const int j = owner[idx[m]];
        if (j == i) continue;
        if (first[j] < 0) first[j] = d[m];
        else if (second[j] < 0) second[j] = d[m];
      }
      const float bound = d[k - 1];  // no scan's second nearest that is not listed is nearer than this
      for (int j = 0; j < n; ++j) {
        if (first[j] < 0) continue;
        const float d2 = second[j] >= 0 ? second[j] : bound;
        votes(i, j) += first[j] < ratio2 * d2;
      }
    }
  }
  return votes;
}

}  // namespace scanreg
