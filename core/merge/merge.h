// Registered scans to one surface (SPEC §4): range-image patches, the signed distance field
// (maximum likelihood or TSDF), optional smoothing, Marching Cubes, small-piece removal.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/merge/merge_estimate.h"
#include "core/merge/merge_options.h"
#include "core/merge/mesh.h"

namespace scanreg::merge {

struct MergeResult {
  Mesh mesh;
  std::size_t scans = 0;             // scans merged
  // Tiled (MergeOptions::tile_blocks): points and patches summed over the tiles, each tile's margin
  // counted in it; blocks and known voxels of each tile's own blocks; field_bytes the largest tile's.
  std::size_t input_points = 0;      // their valid points (thinned where denser than the grid)
  std::size_t patches = 0;           // range-image triangles used
  std::size_t blocks = 0;            // allocated 8^3 blocks
  std::size_t known_voxels = 0;      // grid points with a field value
  std::size_t field_bytes = 0;       // memory of the sparse grid
  std::size_t removed_triangles = 0;  // in small pieces
  std::size_t moving_points = 0;     // points left out as moving objects (MergeOptions::remove_moving)
  std::vector<std::size_t> moving_per_scan;  // the same per merged scan, in their order
  double seconds = 0.0;
  MergeEstimate estimate;            // what was expected before the merge (pipeline::MergeScans)
};

// All scans must be registered (world_from_scan set). Cancelled: kCancelled, no result.
Expected<MergeResult> MergeScanSet(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel);
// The same without copying: the scans to merge, by pointer.
Expected<MergeResult> MergeScanSet(const std::vector<const Scan*>& scans, const MergeOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::merge
