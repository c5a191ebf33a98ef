#include "core/pipeline/candidate_pairs.h"

#include <algorithm>
#include <memory>
#include <set>

#include "core/features/pair_votes.h"
#include "core/registration/point_index.h"

namespace scanreg::pipeline {

Eigen::MatrixXi CandidateVotes(const std::vector<PreparedScan>& scans, double ratio) {
  std::vector<DescriptorSet> sets;
  for (const PreparedScan& p : scans) sets.push_back({p.features.descriptors.data(), p.features.size()});
  PairVoteOptions options;
  options.ratio = ratio;
  return PairVotes(sets, kSiftDescriptorSize, options);
}

std::vector<std::pair<int, int>> CandidatePairs(const Eigen::MatrixXi& votes, const std::vector<bool>& has_features,
                                                int per_scan, const std::vector<std::pair<int, int>>& required) {
  const int n = static_cast<int>(votes.rows());
  std::set<std::pair<int, int>> chosen;
  auto add = [&](int a, int b) {
    if (a != b && a >= 0 && b >= 0 && a < n && b < n) chosen.emplace(std::min(a, b), std::max(a, b));
  };
  const bool all = per_scan <= 0 || per_scan >= n - 1;
  for (int i = 0; i < n; ++i) {
    std::vector<int> others;
    for (int j = 0; j < n; ++j)
      if (j != i) others.push_back(j);
    const bool every = all || i >= static_cast<int>(has_features.size()) || !has_features[i];
    if (!every) {  // the most votes (both ways) first; ties by index (deterministic)
      std::stable_sort(others.begin(), others.end(), [&](int a, int b) {
        return votes(i, a) + votes(a, i) > votes(i, b) + votes(b, i);
      });
      others.resize(per_scan);
    }
    for (int j : others) add(i, j);
    add(i, i + 1);  // capture order
  }
  for (const auto& [a, b] : required) add(a, b);
  return {chosen.begin(), chosen.end()};
}

std::vector<std::pair<int, int>> OverlappingPairs(const std::vector<std::vector<Eigen::Vector3d>>& samples,
                                                  const std::vector<Eigen::Isometry3d>& world_from_scan,
                                                  double distance_m, double min_overlap) {
  const int n = static_cast<int>(samples.size());
  std::vector<std::unique_ptr<PointIndex>> index(n);
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < n; ++i) index[i] = std::make_unique<PointIndex>(samples[i]);
  std::vector<std::pair<int, int>> all, out;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) all.emplace_back(i, j);
  std::vector<char> overlapping(all.size(), 0);
#pragma omp parallel for schedule(dynamic, 8)
  for (long k = 0; k < static_cast<long>(all.size()); ++k) {
    const auto [i, j] = all[k];
    const Eigen::Isometry3d i_from_j = world_from_scan[i].inverse() * world_from_scan[j];
    overlapping[k] = std::max(SampleOverlap(*index[i], samples[j], i_from_j, distance_m),
                              SampleOverlap(*index[j], samples[i], i_from_j.inverse(), distance_m)) >= min_overlap;
  }
  for (std::size_t k = 0; k < all.size(); ++k)
    if (overlapping[k]) out.push_back(all[k]);
  return out;
}

double PairRecall(const std::vector<std::pair<int, int>>& truth, const std::vector<std::pair<int, int>>& candidates) {
  if (truth.empty()) return 1.0;
  const std::set<std::pair<int, int>> found(candidates.begin(), candidates.end());
  int hit = 0;
  for (const auto& p : truth) hit += found.count({std::min(p.first, p.second), std::max(p.first, p.second)}) > 0;
  return double(hit) / truth.size();
}

}  // namespace scanreg::pipeline
