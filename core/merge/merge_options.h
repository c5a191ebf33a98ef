// Options of the merge (SPEC §4): which signed distance field, its grid, and the mesh clean-up.
#pragma once

#include <algorithm>
#include <cstddef>
#include <optional>
#include <string>

#include "core/common/expected.h"

namespace scanreg::merge {

enum class MergeMethod {
  kMaximumLikelihood,  // S §2.3 / §3.3: maximum-likelihood distance histogram, sign by weighted vote
  kTsdf,               // Curless & Levoy 1996: weighted truncated signed distance averaging (baseline)
  kConsensus,          // the measurements near a grid point vote with their signed plane distances, weighted by
                       // their line-of-sight noise and a kernel of one voxel along the surface (sub-voxel consensus)
};

const char* MergeMethodName(MergeMethod method);
// "ml", "tsdf" or "consensus" (MergeMethodName's names); nothing for any other text.
std::optional<MergeMethod> ParseMergeMethod(const std::string& name);

struct MergeOptions {
  double voxel_m = 0.02;           // metres: edge of a voxel (S's grid interval, §4.1: 0.02)
  // S's ML distance is the default, by measurement (tests/merge, scanreg-bench --section merge):
  // it is watertight on a closed box (RMS 2.5 mm; TSDF 9.8 mm with 758 boundary edges along the
  // box's edges) and closer on the real Stanford bunny (0.24 vs 0.36 mm input-to-surface); TSDF is
  // closer on smooth shapes (sphere 2.6 vs 6.0 mm, plane 5.7 vs 13.1 mm; S's two-plane model
  // 0.012 vs 0.019) and ~25x faster, so large street projects merge with --method tsdf.
  // The consensus is the default: on a simulated street (5 cm voxels) 7.0 mm RMS from the noise-free
  // scene against the input points' 10.0, ML's 15.2 and TSDF's 15.8 (scanreg-bench --section merge).
  MergeMethod method = MergeMethod::kConsensus;
  double sigma_m = 0.012;          // metres: range noise along the line of sight (S §3.1; W's scanner 12 mm)
  double band_m = 0.0;             // metres: field evaluated within this distance of the data; 0 = 3 voxels
  double bin_m = 0.0;              // metres: ML histogram bin width (S §3.3, a user setting); 0 = sigma / 4
  int smooth_iterations = 0;       // passes of a 3x3x3 mean filter over the field (S §3.3, optional)
  bool remove_small_pieces = true;  // drop connected pieces of the mesh with few triangles
  double min_piece_fraction = 0.05;  // a piece is small below this fraction of the largest piece's triangles
  // The field is built and meshed in tiles of this many 8^3-voxel blocks across (x and y; 256 voxels:
  // 5 m at 2 cm), so its memory is one tile's, whatever the project's size (0: one piece).
  int tile_blocks = 32;
  // The consensus leaves a hole where no measurement lies within a voxel along the surface (between
  // samples wider apart than the voxel: far surfaces at a fine voxel). Filled, the field there comes
  // from the nearest range-image triangle or disc; every merge marks such vertices (VertexInfo::gap_m
  // beyond FilledGap). TSDF and ML interpolate over the triangles whatever this says.
  bool fill_holes = false;
  double max_grazing_deg = 85.0;   // degrees: range-image triangles seen more obliquely are not patches
  // metres: returns farther from their scanner are left out (0 = all). Far returns are sparse and
  // noisy, and they spread the field over a large area (the street's ground to 200 m).
  double max_range_m = 0.0;
  // Points of one scan in another scanner's free space (vehicles and people that moved between the
  // scans, stray returns) are left out, so the mesh has no ghosts (pipeline/moving_points.h).
  bool remove_moving = true;
  double moving_margin_m = 0.0;
  // Bytes the merge may take (merge_estimate.h): a merge estimated above it is refused before it
  // starts; 0 = three quarters of the machine's memory.
  std::size_t memory_budget_bytes = 0;  // metres nearer than the other scanner's surface; 0 = max(8 sigma, 2 voxels)
  Status Validate() const;

  double MovingMargin() const { return moving_margin_m > 0.0 ? moving_margin_m : std::max(8.0 * sigma_m, 2.0 * voxel_m); }

  double Band() const { return band_m > 0.0 ? band_m : 3.0 * voxel_m; }
  double Bin() const { return bin_m > 0.0 ? bin_m : sigma_m / 4.0; }
};

}  // namespace scanreg::merge
