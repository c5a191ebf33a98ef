// Registered scans to one surface (SPEC §4): range-image patches, the signed distance field
// (maximum likelihood or TSDF), optional smoothing, Marching Cubes, small-piece removal.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/merge/merge_estimate.h"
#include "core/merge/merge_options.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_spill.h"

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
  // Vertices farther than FilledGap from every scan point, or resting on filled values (vertex_info.h):
  // surface interpolated, not measured — filled holes (MergeOptions::fill_holes) and the insides of
  // wide range-image triangles.
  std::size_t interpolated_vertices = 0;
  std::size_t moving_points = 0;     // points left out as moving objects (MergeOptions::remove_moving)
  std::vector<std::size_t> moving_per_scan;  // the same per merged scan, in their order
  double seconds = 0.0;
  MergeEstimate estimate;            // what was expected before the merge (pipeline::MergeScans)
};

// The scans of a merge, fetched when a step needs them (issue 13, item 5: merge memory bounded by
// a tile, not the project): each is asked for once by a first pass (its extent, spacing and blocks)
// and then once by each tile it reaches, which keeps only the cells that reach the tile. A source
// backed by files (pipeline::ScanStore) reads them again when evicted.
struct ScanSource {
  int count = 0;
  std::function<Expected<std::shared_ptr<const Scan>>(int index)> get;
};
// Scans the caller holds (not copied; they must outlive the merge).
ScanSource ScansInMemory(const std::vector<const Scan*>& scans);

// All scans must be registered (world_from_scan set). Cancelled: kCancelled, no result.
// spill: the mesh is appended there tile by tile (small pieces removed there too) and the result's
// mesh stays empty but for its origin — its memory is then one tile's, whatever the mesh's size.
Expected<MergeResult> MergeScanSet(const ScanSource& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel, MeshSpill* spill = nullptr);
// The same for scans in memory.
Expected<MergeResult> MergeScanSet(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel);
Expected<MergeResult> MergeScanSet(const std::vector<const Scan*>& scans, const MergeOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::merge
