#include "core/pipeline/merge_scans.h"

#include "core/io/las_writer.h"
#include "core/common/log.h"
#include "core/io/text_parse.h"
#include "core/pipeline/moving_points.h"
#include "core/pipeline/scan_previews.h"
#include "core/pipeline/scan_store.h"
#include "core/pipeline/scale_defaults.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/merge/mesh_io.h"

namespace scanreg::pipeline {

namespace {

// Leaves out of `scan` the cells on moving objects and the cells beyond the maximum range: marked
// invalid. Listed points (Scan::list_points) stay, and a cloud seen from several places keeps every
// point: its range from its origin means nothing (issue 34, item 2).
void LeaveOut(Scan& scan, const std::vector<std::uint32_t>& moving, double max_range_m) {
  for (std::uint32_t c : moving)
    if (c < scan.size()) scan.valid[c] = 0;
  if (max_range_m > 0.0 && scan.single_viewpoint) {
    const double max2 = max_range_m * max_range_m;
    for (std::size_t c = 0; c < scan.size(); ++c)
      if (scan.valid[c] && scan.points[c].squaredNorm() > max2) scan.valid[c] = 0;
  }
}

// The merge's account of what it left out (MovingPointCells marks valid points only) and expected.
void Account(const std::vector<std::vector<std::uint32_t>>& moving, const MergeEstimate& estimate,
             Expected<MergeResult>& result) {
  if (!result.ok()) return;
  result->estimate = estimate;
  for (const auto& cells : moving) {
    result->moving_per_scan.push_back(cells.size());
    result->moving_points += cells.size();
  }
}

// The cells on moving objects of each scan (none when options do not remove them, or one scan).
Expected<std::vector<std::vector<std::uint32_t>>> MovingCells(const merge::ScanSource& scans,
                                                              const std::vector<Eigen::Isometry3d>& poses,
                                                              const MergeOptions& options, ProgressSink& progress,
                                                              const CancelToken& cancel) {
  if (!options.remove_moving || scans.count < 2) return std::vector<std::vector<std::uint32_t>>(scans.count);
  progress.Report(0.0, "finding moving objects");
  MovingPointOptions m;
  m.margin_m = options.MovingMargin();
  return MovingPointCells(scans, poses, m, cancel);
}

Status CheckSelection(std::size_t selected, std::size_t scans) {
  if (selected > 0) return Status::Ok();
  return MakeError(ErrorCode::kInvalidArgument, scans == 0
                                                    ? "merge: the project has no scan"
                                                    : "merge: no registered scan to merge (register the project first)");
}

}  // namespace

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
  if (Status s = CheckSelection(selected.size(), scans.size()); !s) return s.error();
  // Refused before any work when it would not fit in memory (issue 16); the estimate is logged.
  MergeEstimate estimate;
  if (Status fits = merge::CheckMergeFits(selected, options, &estimate); !fits) return fits.error();
  LogInfo("merge of " + std::to_string(selected.size()) + " scans: " + estimate.Describe());
  // Points left out: on moving objects (seen through by another scan), and beyond the maximum range,
  // marked invalid in place (the moving ones were found from all points first).
  std::vector<Eigen::Isometry3d> poses;
  for (const Scan* s : selected) poses.push_back(s->world_from_scan);
  auto moving = MovingCells(merge::ScansInMemory(selected), poses, options, progress, cancel);
  if (!moving) return moving.error();
  for (std::size_t k = 0; k < chosen.size(); ++k) LeaveOut(*chosen[k], (*moving)[k], options.max_range_m);
  Expected<MergeResult> result = merge::MergeScanSet(selected, options, progress, cancel);
  Account(*moving, estimate, result);
  return result;
}

Expected<MergeResult> MergeProjectScans(const io::Project& project, const std::vector<int>& which,
                                        const MergeOptions& options, std::size_t scan_budget_bytes,
                                        ProgressSink& progress, const CancelToken& cancel, merge::MeshSpill* spill) {
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = CheckSelection(which.size(), project.scans.size()); !s) return s.error();
  std::vector<int> position(project.scans.size(), -1);  // of each project scan in `which`
  for (std::size_t k = 0; k < which.size(); ++k) {
    const int i = which[k];
    if (i < 0 || std::size_t(i) >= project.scans.size())
      return MakeError(ErrorCode::kInvalidArgument, "merge: scan number " + std::to_string(i) + " is not in the project");
    if (position[i] >= 0)
      return MakeError(ErrorCode::kInvalidArgument, "merge: scan " + project.scans[i].name + " is asked for twice");
    position[i] = int(k);
  }
  // The estimate from the previews (the preview cache: no full read when it holds them).
  MergeEstimate estimate;
  {
    SubProgress preview_progress(progress, 0.0, 0.05);
    auto previews = LoadScanPreviews(project, PreviewCellsPerScan(which.size()), preview_progress, cancel, which);
    if (!previews) return previews.error();
    std::vector<const Scan*> scans;
    std::vector<int> strides;
    for (const ScanPreview& p : *previews) scans.push_back(&p.scan), strides.push_back(p.stride);
    if (Status fits = merge::CheckMergeFits(scans, options, &estimate, strides, spill != nullptr); !fits)
      return fits.error();
  }
  LogInfo("merge of " + std::to_string(which.size()) + " scans: " + estimate.Describe());
  if (spill && estimate.disk_bytes > 0) {  // refused now rather than on a full disk hours later
    // The output is written beside the temporary files while they exist: a PLY about 1.4 times their
    // size (doubles for the vertices' floats), so both must fit.
    const double needed = 2.4 * double(estimate.disk_bytes);
    std::error_code failed;
    const std::filesystem::space_info space = std::filesystem::space(spill->directory(), failed);
    if (!failed && double(space.available) < needed) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "merge: the mesh needs about " + FormatBytes(estimate.disk_bytes) + " of temporary files in " +
                           spill->directory().string() + " and about " +
                           FormatBytes(std::size_t(needed) - estimate.disk_bytes) +
                           " more for the output written beside them, but only " + FormatBytes(space.available) +
                           " is free there; free some space, write the mesh elsewhere, or use a larger --voxel");
    }
  }
  std::vector<Eigen::Isometry3d> poses;
  for (int i : which) poses.push_back(project.scans[i].world_from_scan);
  const ScanStore::Reader read_file = ProjectScanReader(project);
  // Moving objects from the scans as read (each with its observers, under the budget).
  Expected<std::vector<std::vector<std::uint32_t>>> moving = std::vector<std::vector<std::uint32_t>>(which.size());
  if (options.remove_moving && which.size() > 1) {
    ScanStore raw = ProjectScanStore(project, scan_budget_bytes);
    merge::ScanSource source{int(which.size()), [&](int k) { return raw.Get(which[k]); }};
    SubProgress moving_progress(progress, 0.05, 0.25);
    moving = MovingCells(source, poses, options, moving_progress, cancel);
    if (!moving) return moving.error();
  }
  // The scans as merged: their left-out points marked when read.
  ScanStore merged(
      ProjectScanHeads(project),
      [&](int i) -> Expected<Scan> {
        Expected<Scan> scan = read_file(i);
        if (scan) LeaveOut(*scan, (*moving)[position[i]], options.max_range_m);
        return scan;
      },
      scan_budget_bytes);
  merge::ScanSource source{int(which.size()), [&](int k) { return merged.Get(which[k]); }};
  SubProgress merge_progress(progress, 0.25, 1.0);
  Expected<MergeResult> result = merge::MergeScanSet(source, options, merge_progress, cancel, spill);
  Account(*moving, estimate, result);
  return result;
}

Status WriteMesh(const std::filesystem::path& path, const Mesh& mesh) { return merge::WriteMeshFile(path, mesh); }

Status WriteMesh(const std::filesystem::path& path, const merge::MeshSource& mesh) {
  return merge::WriteMeshFile(path, mesh);
}

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
  return WritePoints(path, merge::InMemoryMesh(mesh));
}

Status WritePoints(const std::filesystem::path& path, const merge::MeshSource& mesh) {
  if (Status s = ValidatePointsPath(path); !s) return s;
  const std::string ext = io::LowerExtension(path);
  if (ext == ".las") {  // the LAS writer takes its points in memory (24 bytes each)
    io::LasCloud cloud;
    cloud.points.reserve(mesh.vertex_count());
    const Eigen::Vector3d origin = mesh.origin();
    const bool coloured = mesh.coloured();
    if (coloured) cloud.rgb.reserve(mesh.vertex_count());
    if (Status s = mesh.ForEachVertex([&](const Eigen::Vector3f& v, const merge::VertexInfo& info) {
          cloud.points.push_back(origin + v.cast<double>());
          if (coloured) cloud.rgb.push_back(info.colour);
          return Status::Ok();
        });
        !s)
      return s;
    return io::WriteLas(path, cloud);
  }
  return merge::WritePointCloudPly(path, mesh);
}

MergeOptions SizedMergeOptions(const std::vector<const Scan*>& scans, MergeOptions options, double max_seconds,
                               MergeEstimate* estimate, const std::vector<int>& strides) {
  MergeEstimate e;
  if (!scans.empty()) {
    const MergeOptions given = options;
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
    // The range noise shrinks with the voxel (the defaults' 12 mm go with their 2 cm), not below the
    // scans' measured roughness, never above the given noise: a street keeps 12 mm, a 20 cm object
    // scanned at 0.2 mm gets ~0.6 mm.
    const double with_voxel = given.sigma_m * std::min(1.0, options.voxel_m / given.voxel_m);
    options.sigma_m = std::min(given.sigma_m, std::max(scale.noise_m, with_voxel));
  }
  if (estimate) *estimate = e;
  return options;
}

Expected<MergeOptions> SizeMergeToProject(const io::Project& project, const std::vector<int>& which,
                                          MergeOptions options, bool size_voxel, bool size_sigma,
                                          ProgressSink& progress, const CancelToken& cancel) {
  if ((!size_voxel && !size_sigma) || which.empty()) return options;
  Expected<std::vector<ScanPreview>> previews =
      LoadScanPreviews(project, PreviewCellsPerScan(which.size()), progress, cancel, which);
  if (!previews) return previews.error();
  std::vector<const Scan*> scans;
  std::vector<int> strides;
  for (const ScanPreview& p : *previews) scans.push_back(&p.scan), strides.push_back(p.stride);
  MergeOptions base = options;  // sized from the defaults, whatever voxel or noise the user gave
  base.voxel_m = MergeOptions().voxel_m;
  base.sigma_m = MergeOptions().sigma_m;
  const MergeOptions sized = SizedMergeOptions(scans, base, std::numeric_limits<double>::infinity(), nullptr, strides);
  if (size_voxel) options.voxel_m = std::max(1e-4, std::round(sized.voxel_m * 1e4) / 1e4);
  if (size_sigma) options.sigma_m = sized.sigma_m;
  return options;
}

}  // namespace scanreg::pipeline
