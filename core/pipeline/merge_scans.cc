#include "core/pipeline/merge_scans.h"

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
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (use.empty() || use[i]) selected.push_back(&scans[i]);
  }
  if (selected.empty()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     scans.empty() ? "merge: the project has no scan" 
                                   : "merge: no registered scan to merge (register the project first)");
  }
  return merge::MergeScanSet(selected, options, progress, cancel);
}

Status WriteMesh(const std::filesystem::path& path, const Mesh& mesh) { return merge::WriteMeshFile(path, mesh); }

}  // namespace scanreg::pipeline
