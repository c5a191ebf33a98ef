#include "core/merge/merge.h"

#include <algorithm>
#include <chrono>
#include <cmath>

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

namespace {

// The blocks the scans' valid points reach (relative to their patch origin), widened by the band.
SparseGrid::Bounds DataBlocks(const std::vector<const Scan*>& scans, const Eigen::Vector3d& origin, double voxel_m,
                              double band_m) {
  Eigen::AlignedBox3d box;
  for (const Scan* s : scans) {
    Eigen::Isometry3d shifted = s->world_from_scan;
    shifted.translation() -= origin;
    for (std::size_t i = 0; i < s->size(); ++i)
      if (s->valid[i]) box.extend(shifted * s->points[i].cast<double>());
  }
  const double block_m = voxel_m * SparseGrid::kBlock;
  auto key = [&](const Eigen::Vector3d& p) {
    return BlockKey{int(std::floor(p.x() / block_m)), int(std::floor(p.y() / block_m)), int(std::floor(p.z() / block_m))};
  };
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(band_m + voxel_m);
  return {key(box.min() - pad), key(box.max() + pad)};
}

// One tile: its own blocks' cubes into `builder`, from patches and a field built around it only.
Status MergeTile(const std::vector<const Scan*>& scans, const MergeOptions& options, const SparseGrid::Bounds& own,
                 const SparseGrid::Bounds& data, double reach_m, const TileInputs& inputs, MeshBuilder* builder,
                 MergeResult* result, ProgressSink& progress, const CancelToken& cancel) {
  // Halo: the cubes of `own` read one more grid point; the sign fix reads 26 neighbours; each
  // smoothing pass one more. Two blocks and a block per 8 passes keep `own`'s values exact.
  const int halo = 2 + (options.smooth_iterations + SparseGrid::kBlock - 1) / SparseGrid::kBlock;
  SparseGrid::Bounds field = own;
  field.lo = {own.lo.x - halo, own.lo.y - halo, data.lo.z - halo};
  field.hi = {own.hi.x + halo, own.hi.y + halo, data.hi.z + halo};
  const double block_m = options.voxel_m * SparseGrid::kBlock;
  // Every patch within the field's candidate radius of a field block, with whole triangles.
  const Eigen::AlignedBox3f keep(
      Eigen::Vector3f(float(field.lo.x * block_m - reach_m), float(field.lo.y * block_m - reach_m),
                      float(field.lo.z * block_m - reach_m)),
      Eigen::Vector3f(float((field.hi.x + 1) * block_m + reach_m), float((field.hi.y + 1) * block_m + reach_m),
                      float((field.hi.z + 1) * block_m + reach_m)));
  auto patches = BuildRangePatches(scans, options.max_grazing_deg, cancel, options.voxel_m, &keep, &inputs);
  if (!patches) return patches.error();
  if (patches->patches.empty()) return Status::Ok();
  result->input_points += patches->points.size();  // with the tile's margin
  result->patches += patches->patches.size();
  auto grid = ComputeField(*patches, options, progress, cancel, &field);
  if (!grid) return grid.error();
  result->field_bytes = std::max(result->field_bytes, grid->MemoryBytes());  // the peak: one tile's
  for (std::size_t b = 0; b < grid->num_blocks(); ++b) {
    if (!own.Contains(grid->block(b).key)) continue;
    ++result->blocks;
    for (float w : grid->block(b).weight) result->known_voxels += w > 0.0f;
  }
  builder->Add(*grid, &own);
  return Status::Ok();
}

}  // namespace

Expected<MergeResult> MergeScanSet(const std::vector<const Scan*>& scans, const MergeOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = options.Validate(); !s) return s.error();
  for (const Scan* s : scans) {
    if (Status v = s->Validate(); !v) return v.error();
  }
  MergeResult result;
  result.scans = scans.size();
  progress.Report(0.0, "meshing the range images");
  const Eigen::Vector3d origin = PatchOrigin(scans);
  const SparseGrid::Bounds data = DataBlocks(scans, origin, options.voxel_m, options.Band());
  const int tile = options.tile_blocks;
  const int tiles_x = tile > 0 ? (data.hi.x - data.lo.x + tile) / tile : 1;
  const int tiles_y = tile > 0 ? (data.hi.y - data.lo.y + tile) / tile : 1;
  MeshBuilder builder;
  if (tiles_x * tiles_y <= 1) {  // one piece
    auto patches = BuildRangePatches(scans, options.max_grazing_deg, cancel, options.voxel_m);
    if (!patches) return patches.error();
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
    builder.Add(*grid);
  } else {  // tile by tile (issue 13, item 5): memory of one tile's patches and field
    const double reach = CandidateRadius(options) + MaxPatchEdge(scans, options.voxel_m) + options.voxel_m;
    const int count = tiles_x * tiles_y;
    const TileInputs inputs = PrepareTileInputs(scans);
    for (int t = 0; t < count; ++t) {
      if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
      const int tx = t % tiles_x, ty = t / tiles_x;
      SparseGrid::Bounds own;
      own.lo = {data.lo.x + tx * tile, data.lo.y + ty * tile, data.lo.z};
      own.hi = {std::min(data.hi.x, own.lo.x + tile - 1), std::min(data.hi.y, own.lo.y + tile - 1), data.hi.z};
      SubProgress tile_progress(progress, 0.95 * t / count, 0.95 * (t + 1) / count);
      if (Status s = MergeTile(scans, options, own, data, reach, inputs, &builder, &result, tile_progress, cancel); !s)
        return s.error();
    }
  }
  result.mesh = std::move(builder.mesh());
  result.mesh.origin = origin;
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
