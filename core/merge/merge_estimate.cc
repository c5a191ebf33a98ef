#include "core/merge/merge_estimate.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>
#include <unordered_map>

#include "core/common/memory_gate.h"
#include "core/merge/sparse_grid.h"

namespace scanreg::merge {
namespace {

// Measured on simulated streets and the demo (scanreg-bench --section merge prints estimate and
// measurement side by side): patch points per field block after the range images' thinning, bytes
// per patch point (point, two triangles, hash), mesh bytes per block, seconds per block and thread.
constexpr double kPatchPointsPerBlock = 160.0;
constexpr double kBytesPerPatchPoint = 80.0;
constexpr double kMeshBytesPerBlock = 2400.0;
// A spilled mesh's temporary files (12 bytes a vertex and a triangle): 886 and ~1000 bytes a block
// on the 11-station street and the 100-station city at 2 cm.
constexpr double kSpillBytesPerBlock = 1000.0;
constexpr double kSecondsPerBlockMl = 3e-3;
// The consensus: 52 CPU s over 42,952 blocks on the 6-station street at 5 cm (1.2e-3), with ML's margin.
constexpr double kSecondsPerBlockConsensus = 1.5e-3;
constexpr double kSecondsPerBlockTsdf = 1.4e-4;  // range-image projection gated per block
// Points merged as discs (a scan's listed points, every point of a cloud seen from several places):
// their normals from 12 neighbours and their splats, CPU seconds a point — 5.9 s more on 2 threads
// for two 1000x250 stations merged into one 420,820-point PLY than for the stations themselves
// (TSDF, 8 cm); the lists bench (21.6 M points, TSDF 5 cm) took 260 s where this says ~300 s.
constexpr double kSecondsPerDiscPoint = 2.8e-5;
constexpr double kBytesPerCellMask = 1.0;  // the moving-object masks (the left-out points are marked in place)

struct Count {
  std::size_t points = 0, cells = 0, blocks = 0;
  std::size_t disc_points = 0;  // merged as discs (kSecondsPerDiscPoint)
  bool capped = false;
  double tile_share = 1.0;  // the largest tile's share of the blocks (a tiled merge's field at once)
};

// Blocks counted at `voxel` for a merge at merge_voxel (equal, or finer when extrapolating).
Count CountBlocks(const std::vector<const Scan*>& scans, const std::vector<int>& strides, const MergeOptions& options,
                  double voxel, std::size_t cap, double merge_voxel) {
  Count c;
  if (scans.empty()) return c;
  const Eigen::Vector3d origin = scans.front()->world_from_scan.translation();
  BlockCounter counter(voxel, options.band_m > 0.0 ? options.band_m : 3.0 * voxel, cap);
  const double max2 = options.max_range_m > 0.0 ? options.max_range_m * options.max_range_m : INFINITY;
  for (std::size_t k = 0; k < scans.size(); ++k) {
    const Scan* s = scans[k];
    const std::size_t weight = k < strides.size() ? std::size_t(strides[k]) * std::size_t(strides[k]) : 1;
    c.cells += s->size() * weight;
    const Eigen::Isometry3d to_grid = Eigen::Translation3d(-origin) * s->world_from_scan;
    for (std::size_t i = 0; i < s->size(); ++i) {
      if (!s->valid[i] || s->points[i].squaredNorm() > max2) continue;
      c.points += weight;
      if (!s->single_viewpoint) c.disc_points += weight;
      if (!c.capped && !counter.Add((to_grid * s->points[i].cast<double>()).cast<float>())) c.capped = true;
    }
    for (const Eigen::Vector3f& p : s->list_points) {  // no maximum range: LeaveOut keeps them all
      c.points += weight;
      c.disc_points += weight;
      if (!c.capped && !counter.Add((to_grid * p.cast<double>()).cast<float>())) c.capped = true;
    }
  }
  c.blocks = counter.count();
  // Tiles of options.tile_blocks blocks at the merge's voxel, with their margins (merge.cc: two
  // blocks each side): the most blocks one tile's field holds.
  if (options.tile_blocks > 0 && c.blocks > 0) {
    const double tile_m = options.tile_blocks * SparseGrid::kBlock * merge_voxel;
    const double block_m = SparseGrid::kBlock * voxel;
    std::unordered_map<BlockKey, std::size_t, BlockKeyHash> per_tile;
    std::size_t most = 0;
    for (const BlockKey& k : counter.keys()) {
      const BlockKey tile{int(std::floor(k.x * block_m / tile_m)), int(std::floor(k.y * block_m / tile_m)), 0};
      most = std::max(most, ++per_tile[tile]);
    }
    const double margin = std::pow((options.tile_blocks + 4.0) / options.tile_blocks, 2);
    c.tile_share = std::min(1.0, margin * double(most) / double(c.blocks));
  }
  return c;
}

MergeEstimate Estimate(const std::vector<const Scan*>& scans, const std::vector<int>& strides,
                       const MergeOptions& options, double voxel, std::size_t cap, bool mesh_on_disk) {
  MergeEstimate e;
  Count c = CountBlocks(scans, strides, options, voxel, cap, voxel);
  e.points = c.points;
  e.blocks = c.blocks;
  const std::size_t disc_points = c.disc_points;
  // Past the cap: count at coarser voxels until the count fits, once more at twice that voxel, and
  // extrapolate with the exponent the two counts show (2 for a bare surface; less, as the band's
  // blocks do not shrink with the surface's square).
  double coarse = voxel;
  while (c.capped && coarse < 1e4) {
    coarse *= 2.0;
    c = CountBlocks(scans, strides, options, coarse, cap, voxel);
    e.extrapolated = true;
  }
  if (e.extrapolated) {
    const Count coarser = CountBlocks(scans, strides, options, 2.0 * coarse, cap, voxel);
    const double k = coarser.blocks > 0 ? std::clamp(std::log2(double(c.blocks) / double(coarser.blocks)), 1.0, 3.0) : 2.0;
    e.blocks = static_cast<std::size_t>(std::min(1e18, double(c.blocks) * std::pow(coarse / voxel, k)));
  }
  const double blocks = double(e.blocks);
  const double field_blocks = c.tile_share * blocks;  // at once: one tile's
  const double patch_points = std::min(double(e.points), kPatchPointsPerBlock * field_blocks);
  const bool masks = options.remove_moving;
  const double mesh = blocks * kMeshBytesPerBlock;
  const double bytes = field_blocks * (sizeof(SparseGrid::Block) + 48.0) + patch_points * kBytesPerPatchPoint +
                       (mesh_on_disk ? 0.0 : mesh) + (masks ? double(c.cells) * kBytesPerCellMask : 0.0);
  e.bytes = static_cast<std::size_t>(std::min(bytes, 1e18));
  if (mesh_on_disk) e.disk_bytes = static_cast<std::size_t>(std::min(blocks * kSpillBytesPerBlock, 1e18));
  const double threads = std::max(1u, std::thread::hardware_concurrency());
  const double per_block = options.method == MergeMethod::kTsdf        ? kSecondsPerBlockTsdf
                           : options.method == MergeMethod::kConsensus ? kSecondsPerBlockConsensus
                                                                       : kSecondsPerBlockMl;
  e.seconds = (blocks * per_block + double(disc_points) * kSecondsPerDiscPoint) / threads;
  return e;
}

std::string Duration(double s) {
  char buf[32];
  if (s < 90) std::snprintf(buf, sizeof buf, "%.0f s", std::max(1.0, s));
  else if (s < 5400) std::snprintf(buf, sizeof buf, "%.0f min", s / 60);
  else std::snprintf(buf, sizeof buf, "%.1f h", s / 3600);
  return buf;
}

}  // namespace

std::string MergeEstimate::Describe() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "about %s and %s (%s%zu blocks of 8^3 voxels)", FormatBytes(std::size_t(bytes)).c_str(),
                Duration(seconds).c_str(), extrapolated ? "~" : "", blocks);
  if (disk_bytes == 0) return buf;
  return buf + (", the mesh's " + FormatBytes(std::size_t(disk_bytes)) + " on disk");
}

MergeEstimate EstimateMerge(const std::vector<const Scan*>& scans, const MergeOptions& options,
                            std::size_t cap_blocks, const std::vector<int>& strides, bool mesh_on_disk) {
  return Estimate(scans, strides, options, options.voxel_m, cap_blocks, mesh_on_disk);
}

std::size_t DefaultMemoryBudget() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return std::size_t(4) << 30;
  return static_cast<std::size_t>(0.75 * double(pages) * double(page));
}

Status CheckMergeFits(const std::vector<const Scan*>& scans, const MergeOptions& options, MergeEstimate* estimate,
                      const std::vector<int>& strides, bool mesh_on_disk) {
  const std::size_t budget = options.memory_budget_bytes > 0 ? options.memory_budget_bytes : DefaultMemoryBudget();
  // The cap keeps the count's own key set small (~50 bytes a key) and quick: past it the count is
  // extrapolated from a coarser voxel (which errs on the large side: the band does not shrink with
  // the surface's square).
  const std::size_t cap = std::clamp<std::size_t>(budget / sizeof(SparseGrid::Block) + 1, 1000, 500'000);
  *estimate = Estimate(scans, strides, options, options.voxel_m, cap, mesh_on_disk);
  if (estimate->bytes <= budget) return Status::Ok();
  // The smallest voxel that fits: blocks shrink with the voxel's square on surfaces; a few steps.
  double voxel = options.voxel_m;
  MergeEstimate fit = *estimate;
  for (int i = 0; i < 8 && fit.bytes > budget; ++i) {
    voxel *= std::max(1.05, std::sqrt(double(fit.bytes) / (0.9 * double(budget))));
    fit = Estimate(scans, strides, options, voxel, cap, mesh_on_disk);
  }
  char voxels[80];
  std::snprintf(voxels, sizeof voxels, "merge: at a voxel of %.4g m the merge needs ", options.voxel_m);
  std::string what = voxels + estimate->Describe() + ", more than the memory budget of " + FormatBytes(std::size_t(budget)) +
                     " (--max-memory SIZE sets it; the default is 3/4 of this machine's memory). ";
  if (fit.bytes <= budget) {
    // Two significant digits, rounded up (a smaller voxel needs more memory).
    const double unit = std::pow(10.0, std::floor(std::log10(voxel)) - 1.0);
    std::snprintf(voxels, sizeof voxels, "A voxel of %.2g m fits (", std::ceil(voxel / unit - 1e-9) * unit);
    what += voxels + fit.Describe() + "); or merge fewer scans, or set --max-range.";
  } else {
    what += "Merge fewer scans, or set --max-range.";
  }
  return MakeError(ErrorCode::kInvalidArgument, what);
}

}  // namespace scanreg::merge
