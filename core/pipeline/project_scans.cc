#include "core/pipeline/project_scans.h"

#include <map>
#include <utility>

#include "core/io/scan_cache.h"
#include "core/io/scan_file.h"

namespace scanreg::pipeline {

std::filesystem::path ProjectCacheDir(const io::Project& project) {
  return project.file.empty() ? std::filesystem::path() : project.file.parent_path() / ".scanreg-cache";
}

Expected<std::vector<Scan>> LoadProjectScans(const io::Project& project, ProgressSink& progress,
                                             const CancelToken& cancel, std::vector<int> which) {
  if (which.empty())
    for (std::size_t i = 0; i < project.scans.size(); ++i) which.push_back(static_cast<int>(i));
  std::map<std::filesystem::path, std::vector<Scan>> files;
  // How often each (file, scan in file) is asked for: its last use takes the scan instead of a copy.
  std::map<std::pair<std::filesystem::path, int>, int> uses;
  for (int i : which)
    if (i >= 0 && i < static_cast<int>(project.scans.size()))
      ++uses[{project.scans[i].path, project.scans[i].index_in_file}];
  std::vector<Scan> scans;
  scans.reserve(which.size());
  for (std::size_t k = 0; k < which.size(); ++k) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "loading scans cancelled");
    if (which[k] < 0 || which[k] >= static_cast<int>(project.scans.size()))
      return MakeError(ErrorCode::kInvalidArgument, "scan number " + std::to_string(which[k]) + " is not in the project");
    const io::ProjectScan& ps = project.scans[which[k]];
    SubProgress sub(progress, double(k) / which.size(), double(k + 1) / which.size());
    auto it = files.find(ps.path);
    std::error_code ec;
    if (it == files.end() && !std::filesystem::is_regular_file(ps.path, ec)) {
      return MakeError(ErrorCode::kNotFound, "scan '" + ps.name + "': scan file '" + ps.path.string() +
                                                 "' is missing; move it back, or open the project in scanreg "
                                                 "(it offers to look for the missing files in a folder), or "
                                                 "remove the scan from the project");
    }
    if (it == files.end()) {
      // One scan asked of this file: from the cache, its record alone (a campaign in one E57).
      int asked = 0;
      for (const auto& [file_scan, n] : uses) asked += file_scan.first == ps.path ? n : 0;
      Expected<std::vector<Scan>> read = io::ReadScanFileCached(ps.path, ProjectCacheDir(project), sub, cancel,
                                                                nullptr, asked == 1 ? ps.index_in_file : -1);
      if (!read) return read.error();
      it = files.emplace(ps.path, std::move(*read)).first;
    }
    if (ps.index_in_file < 0 || ps.index_in_file >= static_cast<int>(it->second.size())) {
      return MakeError(ErrorCode::kParseError,
                       "scan '" + ps.name + "': file '" + ps.path.string() + "' holds " +
                           std::to_string(it->second.size()) + " scan(s), not scan number " +
                           std::to_string(ps.index_in_file + 1) + "; re-create the project from the file");
    }
    Scan& in_file = it->second[ps.index_in_file];
    Scan scan = --uses[{ps.path, ps.index_in_file}] == 0 ? std::move(in_file) : in_file;
    scan.name = ps.name;
    scan.world_from_scan = ps.world_from_scan;
    scan.reference_world_from_scan = ps.reference_world_from_scan;
    scans.push_back(std::move(scan));
  }
  progress.Report(1.0, "scans loaded");
  return scans;
}

std::vector<std::string> MissingScanFiles(const io::Project& project) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const io::ProjectScan& s : project.scans)
    if (!std::filesystem::is_regular_file(s.path, ec)) out.push_back(s.name);
  return out;
}

int RelinkFromFolder(io::Project& project, const std::filesystem::path& folder) {
  int found = 0;
  std::error_code ec;
  for (io::ProjectScan& s : project.scans) {
    if (std::filesystem::is_regular_file(s.path, ec)) continue;
    const std::filesystem::path candidate = std::filesystem::absolute(folder / s.path.filename()).lexically_normal();
    if (!std::filesystem::is_regular_file(candidate, ec)) continue;
    s.path = candidate;
    ++found;
  }
  return found;
}

Expected<Scan> RelinkScan(io::Project& project, const std::string& scan, const std::filesystem::path& file,
                          const Scan* current, ProgressSink& progress, const CancelToken& cancel) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  const std::filesystem::path path = std::filesystem::absolute(file).lexically_normal();
  Expected<std::vector<Scan>> read = io::ReadScanFile(path, progress, cancel);
  if (!read) return read.error();
  io::ProjectScan& ps = project.scans[s];
  if (ps.index_in_file >= static_cast<int>(read->size())) {
    return MakeError(ErrorCode::kInvalidArgument, "'" + path.string() + "' holds " + std::to_string(read->size()) +
                                                      " scan(s); '" + scan + "' was scan number " +
                                                      std::to_string(ps.index_in_file + 1) +
                                                      " of its file: choose the file it came from");
  }
  Scan out = std::move((*read)[ps.index_in_file]);
  if (current && (current->rows != out.rows || current->cols != out.cols)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "'" + path.string() + "' holds a " + std::to_string(out.rows) + " x " + std::to_string(out.cols) +
                         " scan; '" + scan + "' is " + std::to_string(current->rows) + " x " +
                         std::to_string(current->cols) + ": not the same scan");
  }
  ps.path = path;
  out.name = ps.name;
  out.world_from_scan = ps.world_from_scan;
  out.reference_world_from_scan = ps.reference_world_from_scan;
  return out;
}

}  // namespace scanreg::pipeline
