#include "core/pipeline/merge_scans.h"

#include "core/pipeline/scale_defaults.h"

#include "core/io/las_writer.h"
#include "core/common/log.h"
#include "core/io/text_parse.h"
#include "core/pipeline/moving_points.h"
#include "core/pipeline/scale_defaults.h"

#include <algorithm>
#include <string>

#include "core/merge/mesh_io.h"

namespace scanreg::pipeline {

Expected<MergeResult> MergeScans(std::vector<Scan> scans, const std::vector<bool>& use,
                                 const MergeOptions& options, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (!use.empty() && use.size() != scans.size()) {
    return MakeError(ErrorCode::kInvalidArgument, "merge: " + std::to_string(use.size()) + " selection flags for " +
                                                      std::to_string(scans.size()) + " scans");
  }
  std::vector<Scan*> chosen;
  for (std::size_t i = 0; i < scans.size(); ++i)
    if (use.empty() || use[i]) chosen.push_back(&scans[i]);
  const std::vector<const Scan*> selected(chosen.begin(), chosen.end());
  if (selected.empty()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     scans.empty() ? "merge: the project has no scan"
                                   : "merge: no registered scan to merge (register the project first)");
  }
  // Refused before any work when it would not fit in memory (issue 16); the estimate is logged.
  MergeEstimate estimate;
  if (Status fits = merge::CheckMergeFits(selected, options, &estimate); !fits) return fits.error();
  LogInfo("merge of " + std::to_string(selected.size()) + " scans: " + estimate.Describe());
  // Points left out: beyond the maximum range, and on moving objects (seen through by another scan).
  std::vector<std::vector<std::uint8_t>> moving;
  if (options.remove_moving && selected.size() > 1) {
    progress.Report(0.0, "finding moving objects");
    MovingPointOptions m;
    m.margin_m = options.MovingMargin();
    moving = MovingPointMasks(selected, m, cancel);
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled");
  }
  // The left-out points marked invalid in place (the masks were computed from all of them first).
  std::vector<std::size_t> moving_per_scan(selected.size(), 0);
  const double max2 = options.max_range_m * options.max_range_m;
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    Scan& scan = *chosen[k];
    for (std::size_t c = 0; c < scan.size(); ++c) {
      if (!scan.valid[c]) continue;
      if (!moving.empty() && moving[k][c]) {
        scan.valid[c] = 0;
        ++moving_per_scan[k];
      } else if (options.max_range_m > 0.0 && scan.points[c].squaredNorm() > max2) {
        scan.valid[c] = 0;
      }
    }
  }
  moving = {};
  Expected<MergeResult> result = merge::MergeScanSet(selected, options, progress, cancel);
  if (result.ok()) {
    result->moving_per_scan = moving_per_scan;
    result->estimate = estimate;
    for (std::size_t n : moving_per_scan) result->moving_points += n;
  }
  return result;
}

Status WriteMesh(const std::filesystem::path& path, const Mesh& mesh) { return merge::WriteMeshFile(path, mesh); }

Status ValidateMeshPath(const std::filesystem::path& path) {
  const std::string ext = io::LowerExtension(path);
  if (ext == ".ply" || ext == ".obj" || ext == ".stl") return Status::Ok();
  return MakeError(ErrorCode::kInvalidArgument,
                   "merge: the mesh is written as PLY, OBJ or STL; give the mesh file a .ply, .obj or .stl name, "
                   "not " +
                       path.string());
}

Status ValidatePointsPath(const std::filesystem::path& path) {
  const std::string ext = io::LowerExtension(path);
  if (ext == ".ply" || ext == ".las") return Status::Ok();
  return MakeError(
      ErrorCode::kInvalidArgument,
      "merge: the merged point cloud is written as PLY or LAS; give the points file a .ply or .las name, not " +
          path.string());
}

Status WritePoints(const std::filesystem::path& path, const Mesh& mesh) {
  if (Status s = ValidatePointsPath(path); !s) return s;
  const std::string ext = io::LowerExtension(path);
  if (ext == ".las") {
    io::LasCloud cloud;
    for (const auto& v : mesh.vertices) cloud.points.push_back(mesh.origin + v.cast<double>());
    return io::WriteLas(path, cloud);
  }
  return merge::WritePointCloudPly(path, mesh.origin, mesh.vertices);
}

MergeOptions SizedMergeOptions(const std::vector<const Scan*>& scans, MergeOptions options, double max_seconds,
                               MergeEstimate* estimate, const std::vector<int>& strides) {
  MergeEstimate e;
  if (!scans.empty()) {
    const ProjectScale scale = MeasureProjectScale(scans);
    const int finest = strides.empty() ? 1 : std::max(1, *std::min_element(strides.begin(), strides.end()));
    const double from_data = std::max(scale.extent_m / 1000.0, scale.spacing_m / finest);
    if (from_data > 0) options.voxel_m = std::clamp(from_data, 1e-3, std::max(1e-3, options.voxel_m));
    const std::size_t budget =
        options.memory_budget_bytes > 0 ? options.memory_budget_bytes : merge::DefaultMemoryBudget();
    // Counted up to 500 k blocks, extrapolated past them (erring large, as CheckMergeFits does): a
    // fine voxel on a 100-station project would otherwise count tens of millions of blocks per step.
    for (int doubling = 0; doubling < 12; ++doubling) {
      e = merge::EstimateMerge(scans, options, 500'000, strides);
      if (e.seconds <= max_seconds && e.bytes <= budget / 2) break;
      // Too slow: blocks shrink at most with the voxel's square, so a step of sqrt(too slow) lands
      // at or below the voxel that fits (a few steps, not a dozen counts). Too large: doubled.
      const double over = e.seconds / max_seconds;
      options.voxel_m *= over > 1.0 ? std::max(1.25, std::sqrt(over)) : 2.0;
    }
  }
  if (estimate) *estimate = e;
  return options;
}

}  // namespace scanreg::pipeline
