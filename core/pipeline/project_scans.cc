#include "core/pipeline/project_scans.h"

#include <map>

#include "core/io/scan_file.h"

namespace scanreg::pipeline {

Expected<std::vector<Scan>> LoadProjectScans(const io::Project& project, ProgressSink& progress,
                                             const CancelToken& cancel) {
  std::map<std::filesystem::path, std::vector<Scan>> files;
  std::vector<Scan> scans;
  scans.reserve(project.scans.size());
  for (std::size_t i = 0; i < project.scans.size(); ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "loading scans cancelled");
    const io::ProjectScan& ps = project.scans[i];
    SubProgress sub(progress, double(i) / project.scans.size(), double(i + 1) / project.scans.size());
    auto it = files.find(ps.path);
    if (it == files.end()) {
      Expected<std::vector<Scan>> read = io::ReadScanFile(ps.path, sub, cancel);
      if (!read) return read.error();
      it = files.emplace(ps.path, std::move(*read)).first;
    }
    if (ps.index_in_file < 0 || ps.index_in_file >= static_cast<int>(it->second.size())) {
      return MakeError(ErrorCode::kParseError,
                       "scan '" + ps.name + "': file '" + ps.path.string() + "' holds " +
                           std::to_string(it->second.size()) + " scan(s), not scan number " +
                           std::to_string(ps.index_in_file + 1) + "; re-create the project from the file");
    }
    Scan scan = it->second[ps.index_in_file];  // copy: a file's scans may be used once each
    scan.name = ps.name;
    scan.world_from_scan = ps.world_from_scan;
    scan.reference_world_from_scan = ps.reference_world_from_scan;
    scans.push_back(std::move(scan));
  }
  progress.Report(1.0, "scans loaded");
  return scans;
}

}  // namespace scanreg::pipeline
