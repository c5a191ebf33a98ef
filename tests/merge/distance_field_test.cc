// The field computed in groups of grid points (one candidate query per 4^3 group; for TSDF, one
// gate of scans per block) against the same formulas evaluated point by point from
// RangePatches::Candidates and a brute-force gate: identical magnitudes and weights, on a sphere
// seen from six noisy views.
#include "core/merge/distance_field.h"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/merge/merge_test_util.h"

namespace scanreg::merge {
namespace {

class GroupedField : public ::testing::TestWithParam<MergeMethod> {};

TEST_P(GroupedField, EqualsPerPointEvaluation) {
  const Eigen::Vector3d c(2.0, -1.0, 0.5);
  const double r = 0.5, sigma = 0.01;
  std::vector<const Scan*> ptrs;
  std::vector<Scan> scans;
  for (const auto& eye : test::AllAroundEyes(c, 3.0)) {
    if (scans.size() == 6) break;  // the axis views
    scans.push_back(test::MakeWindowScan(test::SphereCaster(c, r), eye, c, 50, 50, 0.2, sigma,
                                         31 + unsigned(scans.size()), "v" + std::to_string(scans.size())));
  }
  for (const Scan& s : scans) ptrs.push_back(&s);
  MergeOptions options;
  options.voxel_m = 0.04;
  options.sigma_m = sigma;
  options.method = GetParam();
  CancelToken cancel;
  NullProgress progress;
  auto patches = BuildRangePatches(ptrs, options.max_grazing_deg, cancel, options.voxel_m);
  ASSERT_TRUE(patches) << patches.error().ToString();
  auto grid = ComputeField(*patches, options, progress, cancel);
  ASSERT_TRUE(grid) << grid.error().ToString();
  patches->BuildHash(CandidateRadius(options));  // TSDF with range images needs none: built here for the reference
  // TSDF's gate, brute force: the scans with a point within the band (per axis) of a grid point of the block.
  const double band = options.Band(), h = options.voxel_m;
  auto near_scans = [&](const BlockKey& key) {
    std::vector<int> near;
    const Eigen::Vector3f lo = grid->Position(key, 0, 0, 0), hi = grid->Position(key, 7, 7, 7);
    for (std::size_t s = 0; s + 1 < patches->scan_begin.size(); ++s) {
      for (std::size_t i = patches->scan_begin[s]; i < patches->scan_begin[s + 1]; ++i) {
        const Eigen::Vector3f& p = patches->points[i];
        bool reach = true;
        for (int a = 0; a < 3; ++a) reach = reach && p[a] + band >= lo[a] - 1e-4 * h && p[a] - band <= hi[a] + 1e-4 * h;
        if (reach) {
          near.push_back(int(s));
          break;
        }
      }
    }
    return near;
  };
  std::vector<int> candidates;
  std::size_t known = 0, unknown = 0, sign_flips = 0, magnitude_differs = 0, weight_differs = 0, known_differs = 0;
  for (std::size_t bi = 0; bi < grid->num_blocks(); ++bi) {
    const SparseGrid::Block& b = grid->block(bi);
    const std::vector<int> near = near_scans(b.key);
    for (int l = 0; l < SparseGrid::kVoxels; ++l) {
      const int x = l % 8, y = (l / 8) % 8, z = l / 64;
      const Eigen::Vector3f p = grid->Position(b.key, x, y, z);
      patches->Candidates(p, CandidateRadius(options), &candidates);
      float d = 0.0f, w = 0.0f;
      if (GetParam() == MergeMethod::kMaximumLikelihood) {
        w = MaximumLikelihoodDistance(*patches, p, options, candidates, &d) ? 1.0f : 0.0f;
      } else if (GetParam() == MergeMethod::kConsensus) {
        if (!ConsensusDistance(*patches, p, options, candidates, &d, &w)) w = 0.0f;
      } else {
        w = TsdfDistance(*patches, p, options, near.data(), near.data() + near.size(), candidates, &d);
      }
      const bool grid_known = b.weight[l] > 0.0f;
      if (grid_known != (w > 0.0f)) ++known_differs;
      if (!grid_known) {
        ++unknown;
        continue;
      }
      ++known;
      magnitude_differs += std::abs(b.distance[l]) != std::abs(d);
      weight_differs += b.weight[l] != w;
      sign_flips += (b.distance[l] > 0.0f) != (d > 0.0f);
    }
  }
  ASSERT_GT(known, 5000u);
  EXPECT_GT(unknown, 0u);  // the band is narrower than the allocated blocks
  EXPECT_EQ(known_differs, 0u);
  EXPECT_EQ(magnitude_differs, 0u);
  EXPECT_EQ(weight_differs, 0u);
  // ComputeField also flips isolated wrong signs far from the surface (FixIsolatedSigns).
  EXPECT_LT(sign_flips, known / 200) << sign_flips << " of " << known;
}

INSTANTIATE_TEST_SUITE_P(Methods, GroupedField,
                         ::testing::Values(MergeMethod::kMaximumLikelihood, MergeMethod::kTsdf, MergeMethod::kConsensus));

}  // namespace
}  // namespace scanreg::merge
