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

// Radius within which a grid point's field depends on the patches: the band, plus 3 sigma for ML, the
// band and a voxel along the surface for the consensus.
double CandidateRadius(const MergeOptions& options);

// S §3.3 for one grid point x (relative to the patches' origin): the maximum-likelihood distance
// with its sign. `candidates` must hold (ascending) every patch within CandidateRadius of x, e.g.
// from RangePatches::Candidates; others in it are ignored. False when no patch lies within the band.
bool MaximumLikelihoodDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                               const std::vector<int>& candidates, float* distance);

// The consensus distance at x (issue 35): every patch within a voxel of x along the surface and the
// band across it votes with the signed distance of x from its centre along the consensus normal of
// the surface nearest x, weighted by a Gaussian of half a voxel along the surface and by its noise
// along the normal (sigma cos(phi)); patches facing away from the nearest one (the far side of a thin
// wall) do not vote. False, and no surface there, when no patch lies within the band or none lies
// within a voxel of x along the surface (a hole stays a hole). `weight`: the sum of the votes' weights.
// The weight of a grid point whose value was filled (MergeOptions::fill_holes), not measured.
inline constexpr float kFilledWeight = 1e-6f;

bool ConsensusDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                       const std::vector<int>& candidates, float* distance, float* weight);

// Curless–Levoy: the average over scans of the distance along each scanner's line of sight from x
// to that scan's surface, truncated to the band. Scans with a range image count when they are in
// [near_begin, near_end) (ComputeField passes the scans with a point within the band of x's block)
// and x projects onto their surface within the band; scans without angles count by the plane of
// their nearest patch within the band among `candidates` (as above), weighted by its cosine to the
// line of sight. Returns the total weight.
float TsdfDistance(const RangePatches& patches, const Eigen::Vector3f& x, const MergeOptions& options,
                   const int* near_begin, const int* near_end, const std::vector<int>& candidates, float* distance);

}  // namespace scanreg::merge
