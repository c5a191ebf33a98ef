// The signed distance field of registered scans on a sparse grid (SPEC §4), positive outside
// (towards the scanners), negative inside: S's maximum-likelihood distance or Curless–Levoy TSDF.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/merge/merge_options.h"
#include "core/merge/range_patches.h"
#include "core/merge/sparse_grid.h"

namespace scanreg::merge {

// Allocates the blocks within options.Band() of the input points and evaluates every grid point
// there, in parallel over blocks; grid points farther than the band from every patch stay unknown.
// Candidate patches are gathered once per 4^3 group of grid points. Progress: at most ~200
// reports; cancel is checked once per block.
Expected<SparseGrid> ComputeField(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                  const CancelToken& cancel);

// The same from prepared patches (RangePatches::BuildHash is called here); with `bounds`, only the
// blocks within them (a tile of a tiled merge: the patches must hold every one within
// CandidateRadius of those blocks, and the result there is the untiled one's).
Expected<SparseGrid> ComputeField(RangePatches& patches, const MergeOptions& options, ProgressSink& progress,
                                  const CancelToken& cancel, const SparseGrid::Bounds* bounds = nullptr);

// Radius within which a grid point's field depends on the patches: the band, plus 3 sigma for ML.
double CandidateRadius(const MergeOptions& options);

// S §3.3 for one grid point x (relative to the patches' origin): the maximum-likelihood distance
// with its sign. `candidates` must hold (ascending) every patch within CandidateRadius of x, e.g.
// from RangePatches::Candidates; others in it are ignored. False when no patch lies within the band.
bool MaximumLikelihoodDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                               const std::vector<int>& candidates, float* distance);

// Curless–Levoy: weighted average over scans of the distance along each scanner's line of sight
// from x to that scan's surface (its range image, or the plane of its nearest patch for scans
// without angles), truncated to the band; only scans with a patch within the band count.
// `candidates` as above. Returns the total weight.
float TsdfDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                   const std::vector<int>& candidates, float* distance);

}  // namespace scanreg::merge
