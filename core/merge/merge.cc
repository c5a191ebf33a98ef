#include "core/merge/merge.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/merge/distance_field.h"
#include "core/merge/marching_cubes.h"
#include "core/merge/range_patches.h"
#include "core/merge/vertex_info.h"

#include <string>

namespace scanreg::merge {

ScanSource ScansInMemory(const std::vector<const Scan*>& scans) {
  ScanSource source;
  source.count = int(scans.size());
  source.get = [scans](int i) -> Expected<std::shared_ptr<const Scan>> {
    return std::shared_ptr<const Scan>(scans[i], [](const Scan*) {});  // not owned
  };
  return source;
}

Expected<MergeResult> MergeScanSet(const std::vector<Scan>& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel) {
  std::vector<const Scan*> ptrs;
  for (const Scan& s : scans) ptrs.push_back(&s);
  return MergeScanSet(ScansInMemory(ptrs), options, progress, cancel);
}

Expected<MergeResult> MergeScanSet(const std::vector<const Scan*>& scans, const MergeOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel) {
  return MergeScanSet(ScansInMemory(scans), options, progress, cancel);
}

namespace {

// What the first pass over the scans finds: the patches' origin (the first scanner with a valid
// point, rounded to a metre: keeps UTM offsets out of the floats), each scan's layout, and the
// blocks their valid points reach widened by the band.
struct FirstPass {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<ScanLayout> layouts;
  SparseGrid::Bounds data;
  double max_patch_edge = 0.0;
};

Expected<FirstPass> ReadLayouts(const ScanSource& scans, const MergeOptions& options, const CancelToken& cancel) {
  FirstPass out;
  out.layouts.resize(scans.count);
  bool have_origin = false;
  std::size_t valid = 0;
  std::string names;
  Eigen::AlignedBox3d box;
  for (int i = 0; i < scans.count; ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
    auto scan = scans.get(i);
    if (!scan) return scan.error();
    const Scan& s = **scan;
    if (Status v = s.Validate(); !v) return v.error();
    names += (names.empty() ? "" : ", ") + s.name;
    if (!have_origin && s.CountPoints() > 0) {
      out.origin = s.world_from_scan.translation().array().round();
      have_origin = true;
    }
    out.layouts[i] = LayoutScan(s, out.origin, true, options.voxel_m, cancel);
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
    const ScanLayout::Discs* discs = out.layouts[i].discs.get();
    valid += out.layouts[i].valid + (discs ? discs->points.size() : 0);
    out.max_patch_edge = std::max(out.max_patch_edge, MaxPatchEdge(out.layouts[i].spacing, options.voxel_m));
    for (const Eigen::AlignedBox3f& b : out.layouts[i].blocks)
      if (!b.isEmpty()) box.extend(b.cast<double>());
    if (discs && !discs->box.isEmpty()) box.extend(discs->box.cast<double>());
  }
  if (valid == 0) {
    return MakeError(ErrorCode::kInvalidArgument, scans.count == 0
                                                      ? "merge: no scan to merge (mark scans registered first)"
                                                      : "merge: the scans to merge (" + names + ") have no valid point");
  }
  const double block_m = options.voxel_m * SparseGrid::kBlock;
  auto key = [&](const Eigen::Vector3d& p) {
    return BlockKey{int(std::floor(p.x() / block_m)), int(std::floor(p.y() / block_m)), int(std::floor(p.z() / block_m))};
  };
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(options.Band() + options.voxel_m);
  out.data = {key(box.min() - pad), key(box.max() + pad)};
  return out;
}

// One tile: its own blocks' cubes into `builder`, from patches and a field built around it only —
// of each scan, only the cells whose blocks may reach the tile.
Status MergeTile(const ScanSource& scans, const FirstPass& first, const MergeOptions& options,
                 const SparseGrid::Bounds& own, double reach_m, MeshBuilder* builder, MergeResult* result,
                 ProgressSink& progress, const CancelToken& cancel) {
  const SparseGrid::Bounds& data = first.data;
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
  std::vector<ScanPiece> pieces;
  for (int i = 0; i < scans.count; ++i) {
    const ScanLayout& layout = first.layouts[i];
    int r0 = 0, r1 = 0, c0 = 0, c1 = 0;  // no cell: its discs only
    const bool cells = layout.valid > 0 && PieceWindow(layout, keep, &r0, &r1, &c0, &c1);
    const bool discs = layout.discs && !layout.discs->box.isEmpty() && layout.discs->box.intersects(keep);
    if (!cells && !discs) continue;
    auto scan = scans.get(i);
    if (!scan) return scan.error();
    ScanPiece piece;
    piece.layout = &layout;
    piece.row0 = r0, piece.col0 = c0;
    if (r0 == 0 && c0 == 0 && r1 == layout.rows && c1 == layout.cols) {
      piece.cells = std::move(*scan);
    } else {
      piece.cells = std::make_shared<const Scan>(CropScan(**scan, r0, r1, c0, c1));
    }
    pieces.push_back(std::move(piece));
  }
  if (pieces.empty()) return Status::Ok();
  auto patches = BuildRangePatches(pieces, first.origin, options.max_grazing_deg, cancel, options.voxel_m, &keep);
  if (!patches) return patches.error();
  pieces.clear();  // the views hold the ranges they need
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
  DescribeVertices(*patches, options.voxel_m, &builder->mesh());
  return Status::Ok();
}

}  // namespace

Expected<MergeResult> MergeScanSet(const ScanSource& scans, const MergeOptions& options, ProgressSink& progress,
                                   const CancelToken& cancel, MeshSpill* spill) {
  const auto t0 = std::chrono::steady_clock::now();
  if (Status s = options.Validate(); !s) return s.error();
  MergeResult result;
  result.scans = scans.count;
  progress.Report(0.0, "reading the scans' extents");
  auto first = ReadLayouts(scans, options, cancel);
  if (!first) return first.error();
  const SparseGrid::Bounds& data = first->data;
  progress.Report(0.02, "meshing the range images");
  const int tile = options.tile_blocks;
  const int tiles_x = tile > 0 ? (data.hi.x - data.lo.x + tile) / tile : 1;
  const int tiles_y = tile > 0 ? (data.hi.y - data.lo.y + tile) / tile : 1;
  MeshBuilder builder;
  auto to_spill = [&]() -> Status {
    if (!spill) return Status::Ok();
    Mesh piece = builder.Take();
    return spill->Append(piece);
  };
  if (tiles_x * tiles_y <= 1) {  // one piece
    std::vector<ScanPiece> pieces;
    for (int i = 0; i < scans.count; ++i) {
      auto scan = scans.get(i);
      if (!scan) return scan.error();
      pieces.push_back({std::move(*scan), 0, 0, &first->layouts[i]});
    }
    auto patches = BuildRangePatches(pieces, first->origin, options.max_grazing_deg, cancel, options.voxel_m);
    if (!patches) return patches.error();
    pieces.clear();
    result.input_points = patches->points.size();
    result.patches = patches->patches.size();
    SubProgress field_progress(progress, 0.04, 0.9);
    auto grid = ComputeField(*patches, options, field_progress, cancel);
    if (!grid) return grid.error();
    result.blocks = grid->num_blocks();
    result.field_bytes = grid->MemoryBytes();
    for (std::size_t b = 0; b < grid->num_blocks(); ++b) {
      for (float w : grid->block(b).weight) result.known_voxels += w > 0.0f;
    }
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
    progress.Report(0.9, "marching cubes");
    builder.Add(*grid);
    grid = MakeError(ErrorCode::kFailed, "freed");
    DescribeVertices(*patches, options.voxel_m, &builder.mesh());
    patches = MakeError(ErrorCode::kFailed, "freed");
    if (Status s = to_spill(); !s) return s.error();
  } else {  // tile by tile (issue 13, item 5): memory of one tile's pieces, patches and field
    const double reach = CandidateRadius(options) + first->max_patch_edge + options.voxel_m;
    const int count = tiles_x * tiles_y;
    for (int t = 0; t < count; ++t) {
      if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
      const int tx = t % tiles_x, ty = t / tiles_x;
      SparseGrid::Bounds own;
      own.lo = {data.lo.x + tx * tile, data.lo.y + ty * tile, data.lo.z};
      own.hi = {std::min(data.hi.x, own.lo.x + tile - 1), std::min(data.hi.y, own.lo.y + tile - 1), data.hi.z};
      SubProgress tile_progress(progress, 0.02 + 0.93 * t / count, 0.02 + 0.93 * (t + 1) / count);
      if (Status s = MergeTile(scans, *first, options, own, reach, &builder, &result, tile_progress, cancel); !s)
        return s.error();
      // The cubes of tiles 0..t are meshed: their shared vertices are needed no more.
      builder.Forget([&](int i, int j) {
        const int bx = int(std::floor(double(i) / SparseGrid::kBlock)), by = int(std::floor(double(j) / SparseGrid::kBlock));
        const int cx = std::clamp((bx - data.lo.x) / tile, 0, tiles_x - 1);
        const int cy = std::clamp((by - data.lo.y) / tile, 0, tiles_y - 1);
        return cy * tiles_x + cx <= t;
      });
      if (Status s = to_spill(); !s) return s.error();
    }
  }
  result.mesh = std::move(builder.mesh());
  result.mesh.origin = first->origin;
  if (options.remove_small_pieces && spill) {
    auto removed = spill->RemoveSmallPieces(options.min_piece_fraction);
    if (!removed) return removed.error();
    result.removed_triangles = *removed;
  } else if (options.remove_small_pieces) {
    result.removed_triangles = RemoveSmallPieces(result.mesh, options.min_piece_fraction);
  }
  if ((spill ? spill->triangle_count() : result.mesh.triangles.size()) == 0) {
    return MakeError(ErrorCode::kFailed,
                     "merge: the field has no zero crossing; the voxel may be too large for the data or the band too "
                     "thin (try a smaller voxel size)");
  }
  auto interpolated = spill ? CountInterpolated(*spill, options.voxel_m)
                            : CountInterpolated(InMemoryMesh(result.mesh), options.voxel_m);
  if (!interpolated) return interpolated.error();
  result.interpolated_vertices = *interpolated;
  progress.Report(1.0, "done");
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace scanreg::merge
