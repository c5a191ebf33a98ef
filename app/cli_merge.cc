// scanreg-cli merge: the registered scans of a project to one mesh (SPEC §4).
#include <chrono>
#include <cstdio>
#include <optional>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/io/output_paths.h"
#include "core/merge/vertex_info.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/scan_store.h"

namespace scanreg::cli {

int RunMerge(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp(
      "merge", "PROJECT.scanreg.json --out MESH.ply|.obj|.stl [options]   merges the registered scans", argv,
      {{"voxel", true, false,
        "METRES   voxel size (default: from the data — a thousandth of the scans' extent, at least their point "
        "spacing, between 1 mm and 2 cm; coarser only when the merge would not fit in memory)"},
       {"method", true, false,
        "consensus|ml|tsdf   sub-voxel consensus of the measurements (default, most accurate), S's maximum-likelihood "
        "distance, or Curless-Levoy TSDF (fastest)"},
       {"max-range", true, false, "METRES   leave out returns farther from their scanner (default: all)"},
       {"sigma", true, false,
        "METRES   range noise along the line of sight (default 0.012, smaller in proportion when the voxel is sized "
        "below 2 cm, not below the scans' measured roughness)"},
       {"smooth", true, false, "N        mean-filter passes over the field (default 0)"},
       {"keep-pieces", false, false, "         keep small disconnected pieces"},
       {"fill-holes", false, false,
        "         fill the consensus's holes between samples wider apart than the voxel from the nearest "
        "measurement (the filled vertices are marked: the PLY's scalar_gap = metres to the nearest scan point)"},
       {"max-memory", true, false,
        "SIZE     refuse a merge estimated above this (e.g. 20G, 900M; a bare number is GB; default: 3/4 of this "
        "machine's memory)"},
       {"memory-budget", true, false,
        "SIZE     hold at most this much of full scans in memory (e.g. 6G, 800M); the others are read again "
        "from the binary scan cache when a tile needs them (default: a quarter of the RAM). The mesh does not "
        "depend on it"},
       {"keep-moving", false, false, "         keep points on moving objects (by default left out: no ghosts of traffic)"},
       {"out", true, false, "FILE     output mesh (.ply, .obj or .stl)"},
       {"points", true, false, "FILE.ply|FILE.las   also write the merged point cloud (the surface's vertices)"}},
      &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "merge: give exactly one project file"));
  }
  const auto out = args->Get("out");
  if (!out) return Fail(MakeError(ErrorCode::kInvalidArgument, "merge: --out MESH.ply|.obj|.stl is required"));
  pipeline::MergeOptions options;
  auto voxel = args->GetDouble("voxel", options.voxel_m, 1e-4, 1000.0);  // 0.1 mm .. 1 km
  if (!voxel) return Fail(voxel.error());
  options.voxel_m = *voxel;
  auto sigma = args->GetDouble("sigma", options.sigma_m, 1e-6, 1.0);  // a range noise beyond 1 m means nothing
  if (!sigma) return Fail(sigma.error());
  options.sigma_m = *sigma;
  auto smooth = args->GetInt("smooth", 0, 0, 100);
  if (!smooth) return Fail(smooth.error());
  options.smooth_iterations = *smooth;
  auto max_range = args->GetDouble("max-range", 0.0, 0.0, 1e6);
  if (!max_range) return Fail(max_range.error());
  options.max_range_m = *max_range;
  if (auto text = args->Get("max-memory")) {  // the same sizes as --memory-budget's
    Expected<std::size_t> parsed = pipeline::ParseMemoryBudget(*text);
    if (!parsed) return Fail(MakeError(parsed.error().code, "merge: --max-memory: " + parsed.error().message));
    options.memory_budget_bytes = *parsed;
  }
  std::size_t scan_budget = pipeline::DefaultMemoryBudget();
  if (auto text = args->Get("memory-budget")) {
    Expected<std::size_t> parsed = pipeline::ParseMemoryBudget(*text);
    if (!parsed) return Fail(MakeError(parsed.error().code, "merge: --memory-budget: " + parsed.error().message));
    scan_budget = *parsed;
  }
  options.remove_small_pieces = !args->Has("keep-pieces");
  options.fill_holes = args->Has("fill-holes");
  options.remove_moving = !args->Has("keep-moving");
  const std::string method = args->Get("method").value_or(merge::MergeMethodName(options.method));
  if (const std::optional<merge::MergeMethod> parsed = merge::ParseMergeMethod(method)) {
    options.method = *parsed;
  } else {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "merge: --method must be consensus, ml or tsdf, not '" + method + "'"));
  }
  if (Status s = options.Validate(); !s) return Fail(s.error());
  const auto points = args->Get("points");
  if (points) {
    if (Status s = pipeline::ValidatePointsPath(*points); !s) return Fail(s.error());
  }
  if (Status s = pipeline::ValidateMeshPath(*out); !s) return Fail(s.error());
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  // Checked before the work: a merge can take minutes, and must never replace what it reads.
  for (const auto& [path, what] :
       {std::make_pair(std::optional<std::string>(out), "merge: --out"), std::make_pair(points, "merge: --points")}) {
    if (!path) continue;
    if (Status s = io::CheckNotAnInput(*path, io::ProjectInputs(*project), what); !s) return Fail(s.error());
  }
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  std::vector<int> registered_scans;  // only these are read
  for (std::size_t i = 0; i < project->scans.size(); ++i)
    if (project->scans[i].registered) registered_scans.push_back(int(i));
  const std::size_t registered = registered_scans.size();
  if (registered == 0 && !project->scans.empty()) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "merge: no scan of " + project->file.string() +
                                                           " is registered or has an imported pose; run "
                                                           "`scanreg-cli register` first"));
  }
  if (!args->Has("voxel") || !args->Has("sigma")) {
    // Sized to the data, as the GUI's merge panel sizes its voxel: a 20 cm object gets millimetres.
    Expected<pipeline::MergeOptions> sized = pipeline::SizeMergeToProject(
        *project, registered_scans, options, !args->Has("voxel"), !args->Has("sigma"), progress, cancel);
    if (!sized) return Fail(sized.error());
    options = *sized;
    const auto metres = [](double v) {
      char text[32];
      std::snprintf(text, sizeof text, "%.4g m", v);
      return std::string(text);
    };
    std::string what;
    if (!args->Has("voxel")) what = "voxel " + metres(options.voxel_m);
    if (!args->Has("sigma")) what += (what.empty() ? "" : ", ") + std::string("range noise ") + metres(options.sigma_m);
    std::printf("merge: sized to the data (--voxel and --sigma choose others): %s\n", what.c_str());
  }
  if (registered < project->scans.size()) {
    std::fprintf(stderr, "merge: %zu of %zu scans are not registered and are left out\n",
                 project->scans.size() - registered, project->scans.size());
  }
  // The mesh goes to temporary files beside the output as the tiles are meshed, and is streamed
  // from there into the outputs: the merge's memory does not grow with the mesh.
  auto spill = merge::MeshSpill::Create(std::filesystem::absolute(*out).parent_path());
  if (!spill) return Fail(spill.error());
  auto result =
      pipeline::MergeProjectScans(*project, registered_scans, options, scan_budget, progress, cancel, spill->get());
  if (!result) return Fail(result.error());
  const merge::MeshSpill& mesh = **spill;
  if (Status s = pipeline::WriteMesh(*out, mesh); !s) return Fail(s.error());
  if (points) {
    if (Status s = pipeline::WritePoints(*points, mesh); !s) return Fail(s.error());
    std::printf("merged point cloud: %zu points -> %s\n", mesh.vertex_count(), points->c_str());
  }
  if (options.remove_moving) {
    std::printf("left out %zu points lying in another scanner's free space (moving objects, stray returns; --keep-moving keeps them):",
                result->moving_points);
    for (std::size_t k = 0; k < registered_scans.size() && k < result->moving_per_scan.size(); ++k)
      std::printf(" %s %zu", project->scans[registered_scans[k]].name.c_str(), result->moving_per_scan[k]);
    std::printf("\n");
  }
  std::printf("merged %zu of %zu scans (%s, voxel %.4g m): %zu triangles, %zu vertices, %.1f s -> %s\n", result->scans,
              project->scans.size(), merge::MergeMethodName(options.method), options.voxel_m,
              mesh.triangle_count(), mesh.vertex_count(), result->seconds, out->c_str());
  std::printf("%zu of %zu vertices (%.1f %%) lie farther than %.4g m (1.5 voxels) from every scan point%s: surface "
              "interpolated, not measured (the PLY's scalar_gap: metres to the nearest scan point, beyond 1.5 voxels where "
              "interpolated; CloudCompare's scalar field \"gap\")\n",
              result->interpolated_vertices, mesh.vertex_count(),
              mesh.vertex_count() ? 100.0 * double(result->interpolated_vertices) / double(mesh.vertex_count()) : 0.0,
              merge::FilledGap(options.voxel_m),
              options.fill_holes ? " or rest on a filled hole (--fill-holes)" : "");
  if (mesh.coloured()) std::printf("vertex colour: the scanners' colour at the nearest coloured scan point\n");
  return 0;
}

}  // namespace scanreg::cli
