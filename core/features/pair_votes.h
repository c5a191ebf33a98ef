// Which scans see the same things, before any pair is matched (issue 13, item 3): an approximate
// confusion matrix from one search over every scan's descriptors at once. All descriptors go into
// one randomized k-d forest (OpenCV FLANN); each query descriptor of scan i finds its k nearest
// descriptors among all scans, and votes for scan j when its nearest descriptor in j passes the ratio
// test against the second nearest in j — or, when j holds only one of the k, against the k-th
// distance overall (a lower bound of j's second distance, so the vote is never looser than the exact
// test). votes(i, j) approaches C(i, j) of W's exhaustive matching from below, at the cost of one
// search per descriptor instead of one per descriptor and scan.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace scanreg {

struct DescriptorSet {
  const float* data = nullptr;  // rows x dim, row-major
  int rows = 0;
};

struct PairVoteOptions {
  double ratio = 0.66;   // the ratio test's t_des
  int neighbours = 24;   // k nearest descriptors per query
  int max_queries = 1500;  // per scan, evenly spread over its rows
  int max_indexed = 3000;  // per scan, evenly spread likewise
  int checks = 128;      // FLANN leaves visited per query
  unsigned seed = 1;     // the forest's randomization: the same seed gives the same votes
};

// votes(i, j): query descriptors of scan i voting for scan j (0 on the diagonal). Sets with fewer
// than 2 rows neither vote nor receive votes.
Eigen::MatrixXi PairVotes(const std::vector<DescriptorSet>& sets, int dim, const PairVoteOptions& options);

}  // namespace scanreg
