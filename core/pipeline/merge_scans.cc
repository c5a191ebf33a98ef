#include "core/pipeline/merge_scans.h"

#include "core/io/las_writer.h"
#include "core/io/text_parse.h"

#include <string>

#include "core/merge/mesh_io.h"

namespace scanreg::pipeline {

Expected<MergeResult> MergeScans(const std::vector<Scan>& scans, const std::vector<bool>& use,
                                 const MergeOptions& options, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (!use.empty() && use.size() != scans.size()) {
    return MakeError(ErrorCode::kInvalidArgument, "merge: " + std::to_string(use.size()) + " selection flags for " +
                                                      std::to_string(scans.size()) + " scans");
  }
  std::vector<const Scan*> selected;
  std::vector<Scan> limited;  // range-limited copies when options.max_range_m is set
  limited.reserve(scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!use.empty() && !use[i]) continue;
    if (options.max_range_m <= 0.0) {
      selected.push_back(&scans[i]);
      continue;
    }
    Scan copy = scans[i];
    const float max2 = static_cast<float>(options.max_range_m * options.max_range_m);
    for (std::size_t c = 0; c < copy.size(); ++c)
      if (copy.valid[c] && copy.points[c].squaredNorm() > max2) copy.valid[c] = 0;
    limited.push_back(std::move(copy));
    selected.push_back(&limited.back());
  }
  if (selected.empty()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     scans.empty() ? "merge: the project has no scan"
                                   : "merge: no registered scan to merge (register the project first)");
  }
  return merge::MergeScanSet(selected, options, progress, cancel);
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

}  // namespace scanreg::pipeline
