#include "core/pipeline/export_clouds.h"

#include <map>

#include "core/io/scan_file.h"

namespace scanreg::pipeline {
namespace {

// The pose moved into the points: p_world = world_from_scan p. The angular grid described the
// scanner's lines of sight, which no longer start at the origin, so it is dropped.
void ApplyPose(Scan& scan) {
  const Eigen::Isometry3f t = scan.world_from_scan.cast<float>();
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) scan.points[i] = t * scan.points[i];
  scan.world_from_scan = Eigen::Isometry3d::Identity();
  scan.angles = AngularGrid{};
}

}  // namespace

Status ExportCloudsOptions::Validate() const {
  if (format != "ptx" && format != "e57" && format != "ply") {
    return MakeError(ErrorCode::kInvalidArgument, "export format must be ptx, e57 or ply, not '" + format + "'");
  }
  if (dir.empty()) return MakeError(ErrorCode::kInvalidArgument, "give an output folder for the exported clouds");
  return Status::Ok();
}

Expected<std::vector<ExportedScan>> ExportClouds(const io::Project& project, const ExportCloudsOptions& options,
                                                 ProgressSink& progress, const CancelToken& cancel) {
  namespace fs = std::filesystem;
  if (Status s = options.Validate(); !s) return s.error();
  std::map<fs::path, std::size_t> last_use;  // scan file -> last registered project scan in it
  for (std::size_t i = 0; i < project.scans.size(); ++i)
    if (project.scans[i].registered) last_use[project.scans[i].path] = i;
  if (last_use.empty()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "no scan of " + project.file.string() + " is registered; run `scanreg-cli register` first");
  }
  std::error_code ec;
  fs::create_directories(options.dir, ec);
  if (ec || !fs::is_directory(options.dir, ec)) {
    return MakeError(ErrorCode::kIoError,
                     "cannot create the folder '" + options.dir.string() + "'; choose a folder you can write to");
  }
  std::map<fs::path, std::vector<Scan>> open_files;
  std::vector<ExportedScan> result;
  const double n = static_cast<double>(project.scans.size());
  for (std::size_t i = 0; i < project.scans.size(); ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "export cancelled");
    const io::ProjectScan& ps = project.scans[i];
    ExportedScan out{ps.name, {}, 0, {}};
    if (!ps.registered) {
      out.skipped = ps.unregistered_reason.empty() ? "not registered" : "not registered: " + ps.unregistered_reason;
      result.push_back(out);
      continue;
    }
    SubProgress read_progress(progress, i / n, (i + 0.5) / n);
    auto file = open_files.find(ps.path);
    if (file == open_files.end()) {
      Expected<std::vector<Scan>> read = io::ReadScanFile(ps.path, read_progress, cancel);
      if (!read) return read.error();
      file = open_files.emplace(ps.path, std::move(*read)).first;
    }
    if (ps.index_in_file < 0 || ps.index_in_file >= static_cast<int>(file->second.size())) {
      return MakeError(ErrorCode::kParseError, "scan '" + ps.name + "': file '" + ps.path.string() + "' holds " +
                                                   std::to_string(file->second.size()) + " scan(s), not scan number " +
                                                   std::to_string(ps.index_in_file + 1));
    }
    Scan scan = file->second[ps.index_in_file];
    if (last_use[ps.path] == i) open_files.erase(file);
    scan.name = ps.name;
    scan.world_from_scan = ps.world_from_scan;
    if (options.apply_poses) ApplyPose(scan);
    out.file = options.dir / (ps.name + "." + options.format);
    for (const io::ProjectScan& input : project.scans) {
      if (fs::exists(out.file, ec) && fs::equivalent(out.file, input.path, ec)) {
        return MakeError(ErrorCode::kInvalidArgument, "exporting '" + ps.name + "' would overwrite the input scan '" +
                                                          input.path.string() + "'; choose another output folder");
      }
    }
    out.points = scan.CountValid();
    SubProgress write_progress(progress, (i + 0.5) / n, (i + 1) / n);
    if (Status s = io::WriteScanFile(out.file, {scan}, write_progress, cancel); !s) return s.error();
    result.push_back(out);
  }
  progress.Report(1.0, "clouds exported");
  return result;
}

}  // namespace scanreg::pipeline
