#include "core/pipeline/export_clouds.h"

#include <algorithm>
#include <cstdio>
#include <map>

#include "core/common/log.h"
#include "core/common/output_set.h"
#include "core/io/las_reader.h"
#include "core/io/las_writer.h"
#include "core/io/scan_file.h"
#include "core/merge/mesh_io.h"

namespace scanreg::pipeline {
namespace {

// The pose moved into the points: p_world = world_from_scan p, as floats (PTX, E57). The angular
// grid described the scanner's lines of sight, which no longer start at the origin, so it is dropped.
// A warning names the scan when floats round its world coordinates by more than 0.1 mm.
void ApplyPose(Scan& scan) {
  double largest = 0;
  scan.ForEachPoint([&](const Eigen::Vector3f& p, float) {
    largest = std::max(largest, (scan.world_from_scan * p.cast<double>()).cwiseAbs().maxCoeff());
  });
  if (merge::FloatRoundingError(largest) > merge::kFloatWarningM) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "world coordinates up to %.0f m are rounded by up to %.2f mm", largest,
                  1e3 * merge::FloatRoundingError(largest));
    LogWarning("scan '" + scan.name + "': " + buf +
               " in 32-bit floats; keep the poses in the header (no --apply-poses) or export ply or las (double)");
  }
  const Eigen::Isometry3f t = scan.world_from_scan.cast<float>();
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) scan.points[i] = t * scan.points[i];
  for (Eigen::Vector3f& p : scan.list_points) p = t * p;
  for (std::size_t i = 0; i < scan.sensor.size(); ++i)
    if (scan.valid[i]) scan.sensor[i] = t * scan.sensor[i];
  for (Eigen::Vector3f& s : scan.list_sensor) s = t * s;
  scan.world_from_scan = Eigen::Isometry3d::Identity();
  scan.angles = AngularGrid{};
}

// A per-point attribute in ForEachPoint's order: the grid's valid cells, then the list.
template <typename T>
std::vector<T> InPointOrder(const Scan& scan, const std::vector<T>& cells, const std::vector<T>& listed) {
  std::vector<T> out;
  out.reserve(scan.CountPoints());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) out.push_back(cells[i]);
  out.insert(out.end(), listed.begin(), listed.end());
  return out;
}

// One scan as LAS: world coordinates (double), intensity from reflectance, colour when the scan has
// one (point format 7), each point's time when the scan has them, point source ID = the scan's number in the project (from 1: LAS reserves 0),
// named in the file's VLR.
Status WriteScanLas(const std::filesystem::path& path, const Scan& scan, std::uint16_t source_id) {
  io::LasCloud cloud;
  scan.ForEachPoint([&](const Eigen::Vector3f& p, float refl) {
    cloud.points.push_back(scan.world_from_scan * p.cast<double>());
    cloud.reflectance.push_back(refl);
  });
  if (scan.HasColour()) cloud.rgb = InPointOrder(scan, scan.colour, scan.list_colour);
  if (scan.HasTime()) {
    cloud.gps_time = InPointOrder(scan, scan.time, scan.list_time);
    cloud.adjusted_gps_time = scan.time_base == io::kAdjustedGpsTime;
    // LAS's GPS time is week seconds or adjusted standard GPS time (the global encoding's bit 0); other
    // times (a PLY's without a base, an E57's without a date) go in as they are, labelled week seconds.
    if (!cloud.adjusted_gps_time && scan.time_base != io::kGpsWeekSeconds)
      LogWarning(path.string() + ": scan '" + scan.name + "' has times in " + scan.TimeBaseText() + ", which LAS cannot name: they are written as they are, in the GPS time field marked as GPS week "
                 "seconds; export ply or e57 to keep the base");
  }
  cloud.source_ids.assign(cloud.points.size(), source_id);  // 1-based: LAS reserves 0
  cloud.source_names.assign(source_id + 1, "");
  cloud.source_names[source_id] = scan.name;
  return io::WriteLas(path, cloud);
}

}  // namespace

bool WorldFormat(const std::string& format) { return format == "ply" || format == "las"; }

Status ExportCloudsOptions::Validate() const {
  if (format != "ptx" && format != "e57" && format != "ply" && format != "las") {
    return MakeError(ErrorCode::kInvalidArgument, "export format must be ptx, e57, ply or las, not '" + format + "'");
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
  OutputSet written;  // the clouds exported so far: removed if the export stops halfway
  const double n = static_cast<double>(project.scans.size());
  for (std::size_t i = 0; i < project.scans.size(); ++i) {
    if (cancel.IsCancelled()) return written.Failed(MakeError(ErrorCode::kCancelled, "export cancelled"));
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
      if (!read) return written.Failed(read.error());
      file = open_files.emplace(ps.path, std::move(*read)).first;
    }
    if (ps.index_in_file < 0 || ps.index_in_file >= static_cast<int>(file->second.size())) {
      return written.Failed(MakeError(ErrorCode::kParseError, "scan '" + ps.name + "': file '" + ps.path.string() +
                                                                  "' holds " + std::to_string(file->second.size()) +
                                                                  " scan(s), not scan number " +
                                                                  std::to_string(ps.index_in_file + 1)));
    }
    Scan scan = file->second[ps.index_in_file];
    if (last_use[ps.path] == i) open_files.erase(file);
    scan.name = ps.name;
    scan.world_from_scan = ps.world_from_scan;
    if (options.apply_poses && !WorldFormat(options.format)) ApplyPose(scan);
    out.file = options.dir / (ps.name + "." + options.format);
    for (const io::ProjectScan& input : project.scans) {
      if (fs::exists(out.file, ec) && fs::equivalent(out.file, input.path, ec)) {
        return written.Failed(MakeError(ErrorCode::kInvalidArgument, "exporting '" + ps.name +
                                                                         "' would overwrite the input scan '" +
                                                                         input.path.string() + "'; choose another output folder"));
      }
    }
    out.points = scan.CountPoints();
    if (scan.HasSensor() && options.format == "las")  // the other formats say it as they write (WriteScanFile)
      LogWarning(out.file.string() + ": scan '" + scan.name + "' has a sensor position per point, which " +
                 options.format + " has no field for: they are left out; export ply to keep them (scalar_x_origin, _y_, _z_)");
    SubProgress write_progress(progress, (i + 0.5) / n, (i + 1) / n);
    written.Track(out.file);
    const Status s = options.format == "las" ? WriteScanLas(out.file, scan, static_cast<std::uint16_t>(i + 1))
                                             : io::WriteScanFile(out.file, {scan}, write_progress, cancel);
    if (!s) return written.Failed(s.error());
    result.push_back(out);
  }
  written.Complete();
  progress.Report(1.0, "clouds exported");
  return result;
}

}  // namespace scanreg::pipeline
