#include "core/merge/merge_options.h"

#include <cmath>
#include <string>

namespace scanreg::merge {

const char* MergeMethodName(MergeMethod method) {
  switch (method) {
    case MergeMethod::kTsdf:
      return "tsdf";
    case MergeMethod::kConsensus:
      return "consensus";
    case MergeMethod::kMaximumLikelihood:
      break;
  }
  return "ml";
}

std::optional<MergeMethod> ParseMergeMethod(const std::string& name) {
  for (MergeMethod m : {MergeMethod::kMaximumLikelihood, MergeMethod::kTsdf, MergeMethod::kConsensus})
    if (name == MergeMethodName(m)) return m;
  return std::nullopt;
}

Status MergeOptions::Validate() const {
  auto bad = [](const std::string& what) { return Status(MakeError(ErrorCode::kInvalidArgument, what)); };
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) {
    return bad("merge: voxel size must be > 0 metres, got " + std::to_string(voxel_m));
  }
  if (!(sigma_m > 0.0) || !std::isfinite(sigma_m)) {
    return bad("merge: range noise sigma must be > 0 metres, got " + std::to_string(sigma_m));
  }
  if (!(band_m >= 0.0) || !std::isfinite(band_m)) return bad("merge: band must be >= 0 metres");
  if (tile_blocks < 0) return bad("merge: tile size must be >= 0 blocks (0: one piece)");
  if (!(max_range_m >= 0.0) || !std::isfinite(max_range_m)) {
    return bad("merge: maximum range must be >= 0 metres (0 = no limit)");
  }
  if (!(moving_margin_m >= 0.0) || !std::isfinite(moving_margin_m)) {
    return bad("merge: the moving-object margin must be >= 0 metres (0 = from the noise and voxel)");
  }
  if (band_m > 0.0 && band_m < voxel_m) return bad("merge: band must be at least one voxel (or 0 for 3 voxels)");
  if (!(bin_m >= 0.0) || !std::isfinite(bin_m)) return bad("merge: histogram bin must be >= 0 metres");
  if (smooth_iterations < 0 || smooth_iterations > 100) {
    return bad("merge: smoothing passes must be in 0..100, got " + std::to_string(smooth_iterations));
  }
  if (!(min_piece_fraction >= 0.0 && min_piece_fraction <= 1.0))
    return bad("merge: min_piece_fraction must be in [0, 1]");
  if (!(max_grazing_deg > 0.0 && max_grazing_deg < 90.0)) return bad("merge: max_grazing_deg must be in (0, 90)");
  // Memory guard: a voxel far below the noise wastes memory without adding detail.
  if (voxel_m < 1e-5) return bad("merge: voxel size below 0.01 mm is not supported");
  return Status::Ok();
}

}  // namespace scanreg::merge
