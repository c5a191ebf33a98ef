// Candidate pairs (issue 13, item 3): only the likely partners' features are matched, and every
// truly overlapping pair (overlap >= 30 % at the true poses) is still considered — matched, or found
// overlapping at the registered poses and refined from them for the global step.
#include "core/pipeline/candidate_pairs.h"

#include <gtest/gtest.h>

#include "core/pipeline/register_project.h"
#include "core/registration/voxel_filter.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {
namespace {

TEST(CandidatePairs, EachScansBestVotedItsCaptureNeighboursAndTheUsersPairs) {
  // Scan 0 shares most with 3, scan 1 with 4, scan 2 with 5; the user links 0 and 5.
  Eigen::MatrixXi votes = Eigen::MatrixXi::Zero(6, 6);
  votes(0, 3) = 90;
  votes(4, 1) = 80;
  votes(2, 5) = votes(5, 2) = 35;
  const std::vector<bool> all_have(6, true);
  const auto pairs = CandidatePairs(votes, all_have, 1, {{5, 0}});
  const std::vector<std::pair<int, int>> expected = {{0, 1}, {0, 3}, {0, 5}, {1, 2}, {1, 4}, {2, 3},
                                                     {2, 5}, {3, 4}, {4, 5}};
  EXPECT_EQ(pairs, expected);
  EXPECT_EQ(CandidatePairs(votes, all_have, 0, {}).size(), 15u) << "0: every pair";
  EXPECT_EQ(CandidatePairs(votes, all_have, 5, {}).size(), 15u) << "as many partners as scans: every pair";
  std::vector<bool> scan2_without(6, true);
  scan2_without[2] = false;  // no SIFT features: nothing to rank it by, so every pair of it
  const auto with_blind = CandidatePairs(votes, scan2_without, 1, {});
  for (int j : {0, 1, 3, 4, 5})
    EXPECT_TRUE(std::count(with_blind.begin(), with_blind.end(), std::make_pair(std::min(2, j), std::max(2, j))))
        << "pair 2-" << j;
}

TEST(CandidatePairs, AStreetRegistersFromItsCandidatePairsAndConsidersEveryOverlappingPair) {
  SimulatedProjectOptions o;
  o.stations = 12;
  o.spacing_m = 8.0;
  o.scanner.cols = 1200;
  o.scanner.rows = 300;
  NullProgress progress;
  auto scans = SimulateProject(o, progress, CancelToken());
  ASSERT_TRUE(scans.ok()) << scans.error().message;
  const int n = static_cast<int>(scans->size());

  // The truth: pairs overlapping by 30 % or more at the true poses.
  std::vector<std::vector<Eigen::Vector3d>> samples;
  std::vector<Eigen::Isometry3d> truth_poses;
  for (const Scan& s : *scans) {
    samples.push_back(VoxelDownsample(ValidPoints(s), 0.2));
    truth_poses.push_back(*s.reference_world_from_scan);
  }
  const auto overlapping = OverlappingPairs(samples, truth_poses, 0.3, 0.3);
  ASSERT_GE(overlapping.size(), static_cast<std::size_t>(n - 1)) << "consecutive stations overlap";
  ASSERT_LT(overlapping.size(), static_cast<std::size_t>(n * (n - 1) / 2)) << "and far ones do not";

  RegisterOptions options;
  options.candidates = 3;
  auto r = RegisterScans(*scans, {}, options, progress, CancelToken());
  ASSERT_TRUE(r.ok()) << r.error().message;
  std::vector<std::pair<int, int>> matched, considered;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (r->confusion(i, j) != kSkippedPair) matched.emplace_back(i, j);
  considered = matched;
  for (const auto& [p, c] : r->pairs_by_overlap) considered.emplace_back(std::min(p, c), std::max(p, c));
  EXPECT_EQ(static_cast<int>(matched.size()), r->pairs_matched);
  EXPECT_EQ(r->pairs_possible, n * (n - 1) / 2);
  EXPECT_LT(r->pairs_matched, r->pairs_possible * 2 / 3) << "candidates are a selection, not every pair";
  EXPECT_LT(PairRecall(overlapping, matched), 0.99) << "the selection alone misses overlapping pairs here, or this "
                                                       "test would not show the overlap step at work";
  EXPECT_GE(PairRecall(overlapping, considered), 0.99) << overlapping.size() << " overlapping pairs";

  const std::vector<ReferenceError> errors = ReferenceErrors(*r, *scans);
  for (int i = 0; i < n; ++i) {
    ASSERT_TRUE(r->scans[i].registered) << r->scans[i].name << ": " << r->scans[i].reason;
    EXPECT_LT(errors[i].position_m, 0.02) << r->scans[i].name;
  }
}

}  // namespace
}  // namespace scanreg::pipeline
