#include "core/merge/merge.h"

#include <chrono>

#include "core/merge/distance_field.h"
#include "core/merge/marching_cubes.h"
#include "core/merge/range_patches.h"

namespace scanreg::merge {

Expected<MergeResult> MergeScanSet(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel) {
  std::vector<const Scan*> ptrs;
  for (const Scan& s : scans) ptrs.push_back(&s);
  return MergeScanSet(ptrs, options, progress, cancel);
}

Expected<MergeResult> MergeScanSet(const std::vector<const Scan*>& scans, const MergeOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = options.Validate(); !s) return s.error();
  for (const Scan* s : scans) {
    if (Status v = s->Validate(); !v) return v.error();
  }
  progress.Report(0.0, "meshing the range images");
  auto patches = BuildRangePatches(scans, options.max_grazing_deg, cancel, options.voxel_m);
  if (!patches) return patches.error();
  MergeResult result;
  result.scans = scans.size();
  result.input_points = patches->points.size();
  result.patches = patches->patches.size();
  SubProgress field_progress(progress, 0.02, 0.9);
  auto grid = ComputeField(*patches, options, field_progress, cancel);
  if (!grid) return grid.error();
  patches = MakeError(ErrorCode::kFailed, "freed");
  result.blocks = grid->num_blocks();
  result.field_bytes = grid->MemoryBytes();
  for (std::size_t b = 0; b < grid->num_blocks(); ++b) {
    for (float w : grid->block(b).weight) result.known_voxels += w > 0.0f;
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
  progress.Report(0.9, "marching cubes");
  result.mesh = ExtractMesh(*grid);
  if (options.remove_small_pieces)
    result.removed_triangles = RemoveSmallPieces(result.mesh, options.min_piece_fraction);
  if (result.mesh.triangles.empty()) {
    return MakeError(ErrorCode::kFailed,
                     "merge: the field has no zero crossing; the voxel may be too large for the data or the band too "
                     "thin (try a smaller voxel size)");
  }
  progress.Report(1.0, "done");
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace scanreg::merge
