// Candidate pairs (issue 13, item 3): which scans' features are matched with which, so that a
// project of N scans matches about N x k pairs instead of N (N - 1) / 2. Partners are ranked by an
// approximate confusion matrix from one search over every scan's SIFT descriptors at once
// (core/features/pair_votes.h); each scan is paired with its k best-voted scans, its neighbours in
// capture order (stations are set up one after the other), and every pair the caller requires (the
// user's links and parent overrides). A scan without SIFT features (no usable reflectance) keeps
// every pair. Pairs that overlap but were not matched are found later at the registered poses
// (LinkSource::overlap_at, registration_driver.h).
#pragma once

#include <Eigen/Geometry>
#include <utility>
#include <vector>

#include "core/pipeline/register_pair.h"

namespace scanreg::pipeline {

// votes(i, j): scan i's SIFT descriptors whose nearest in scan j passes the ratio test (PairVotes).
Eigen::MatrixXi CandidateVotes(const std::vector<PreparedScan>& scans, double ratio);

// The unordered pairs (i < j, ascending) to match: every pair when per_scan is 0 or the selection
// would hold them all anyway, else the union described above (`has_features[i]` false: every pair
// of scan i).
std::vector<std::pair<int, int>> CandidatePairs(const Eigen::MatrixXi& votes, const std::vector<bool>& has_features,
                                                int per_scan, const std::vector<std::pair<int, int>>& required);

// Ground truth for measuring the selection (tests, bench): the pairs {i < j} whose overlap at the
// given poses — the larger of SampleOverlap both ways over each scan's voxel samples (scan frame),
// within distance_m — reaches min_overlap.
std::vector<std::pair<int, int>> OverlappingPairs(const std::vector<std::vector<Eigen::Vector3d>>& samples,
                                                  const std::vector<Eigen::Isometry3d>& world_from_scan,
                                                  double distance_m, double min_overlap);

// The share of `truth` found in `candidates` (1 when truth is empty).
double PairRecall(const std::vector<std::pair<int, int>>& truth, const std::vector<std::pair<int, int>>& candidates);

}  // namespace scanreg::pipeline
