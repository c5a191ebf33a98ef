#include "core/pipeline/create_project.h"

#include <algorithm>
#include <map>
#include <set>

#include "core/common/log.h"
#include "core/common/output_set.h"
#include "core/io/control_file.h"
#include "core/io/e57_writer.h"
#include "core/pipeline/project_edits.h"
#include "core/io/pose_csv.h"
#include "core/io/pose_file.h"
#include "core/io/ptx.h"
#include "core/io/scan_cache.h"
#include "core/io/scan_file.h"
#include "core/pipeline/project_scans.h"
#include "core/io/text_parse.h"

namespace scanreg::pipeline {
namespace {

// A folder of 4x4 matrix files, one per scan named <scan>.txt (what `export-poses --format txt`
// writes), in name order.
Expected<std::vector<io::NamedPose>> ReadMatrixFolder(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.is_regular_file(ec) && io::LowerExtension(e.path()) == ".txt") files.push_back(e.path());
  if (ec) return MakeError(ErrorCode::kIoError, "cannot list the pose folder '" + dir.string() + "': " + ec.message());
  if (files.empty()) {
    return MakeError(ErrorCode::kNotFound, "the pose folder '" + dir.string() + "' holds no <scan>.txt matrix file");
  }
  std::sort(files.begin(), files.end());
  std::vector<io::NamedPose> poses;
  for (const auto& f : files) {
    Expected<Eigen::Isometry3d> t = io::ReadMatrixTxt(f);
    if (!t) return t.error();
    poses.push_back({f.stem().string(), *t, ""});
  }
  return poses;
}

}  // namespace

Expected<std::vector<io::NamedPose>> ReadPoseFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return ReadMatrixFolder(path);
  const std::string ext = io::LowerExtension(path);
  if (ext == ".conf") return io::ReadBunConf(path);
  if (ext == ".json") return io::ReadPosesJson(path);
  if (ext == ".csv") return io::ReadPosesCsv(path);
  if (ext == ".txt") {
    Expected<Eigen::Isometry3d> t = io::ReadMatrixTxt(path);
    if (!t) return t.error();
    return std::vector<io::NamedPose>{{path.stem().string(), *t, ""}};
  }
  return MakeError(ErrorCode::kUnsupported,
                   "pose file '" + path.string() +
                       "' has an unknown extension; use a Stanford .conf, a poses .json or .csv, a 4x4 matrix "
                       "<scan>.txt or a folder of them (every format `export-poses` writes)");
}

namespace {

// Applies each named pose to the scan whose name or file name matches. A pose file may cover more
// scans than the project holds (a .conf of the whole object): poses that match no scan are named in
// a warning; none matching at all is an error (the wrong file).
Status ApplyPoses(const std::filesystem::path& pose_file, const std::vector<io::NamedPose>& poses, bool reference,
                  io::Project& project) {
  std::string unmatched;
  int unmatched_count = 0;
  std::map<std::string, std::string> posed;  // scan name -> the pose entry that set it
  for (const io::NamedPose& pose : poses) {
    bool matched = false;
    for (io::ProjectScan& scan : project.scans) {
      const bool same = scan.name == pose.scan || scan.path.filename().string() == pose.scan ||
                        scan.path.stem().string() == pose.scan;
      if (!same) continue;
      // Two entries for one scan: which one is meant cannot be guessed.
      if (const auto [it, added] = posed.emplace(scan.name, pose.scan); !added) {
        return MakeError(ErrorCode::kInvalidArgument, "pose file '" + pose_file.string() + "' gives scan '" +
                                                          scan.name + "' two poses ('" + it->second + "' and '" +
                                                          pose.scan + "'); keep one");
      }
      if (reference) {
        scan.reference_world_from_scan = pose.world_from_scan;
      } else {
        scan.world_from_scan = pose.world_from_scan;
        scan.registered = scan.imported_pose = true;
        scan.file_up = pose.world_from_scan.linear().transpose() * Eigen::Vector3d::UnitZ();
        scan.unregistered_reason.clear();
      }
      matched = true;
    }
    if (!matched) unmatched += (unmatched_count++ ? ", '" : "'") + pose.scan + "'";
  }
  if (unmatched_count == static_cast<int>(poses.size())) {
    return MakeError(ErrorCode::kNotFound, "pose file '" + pose_file.string() + "' names no scan of the project (" +
                                               unmatched + "); check that it belongs to these scan files");
  }
  if (unmatched_count > 0) {
    LogWarning("pose file '" + pose_file.string() + "': " + std::to_string(unmatched_count) +
               " pose(s) match no scan of the project and were not used: " + unmatched);
  }
  return Status::Ok();
}

}  // namespace

Status AppendScanFiles(io::Project& project, const std::vector<std::filesystem::path>& scan_files,
                       ProgressSink& progress, const CancelToken& cancel, std::vector<std::string>* skipped) {
  io::Project result = project;
  std::set<std::string> names;
  for (const io::ProjectScan& s : result.scans) names.insert(s.name);
  // A problem with one file: an error, or with `skipped` a line of the list and the next file.
  auto refuse = [&](Error e) -> bool {
    if (!skipped || e.code == ErrorCode::kCancelled) return false;
    skipped->push_back(e.message);
    return true;
  };
  for (std::size_t f = 0; f < scan_files.size(); ++f) {
    const std::filesystem::path path = std::filesystem::absolute(scan_files[f]).lexically_normal();
    std::string already;
    for (const io::ProjectScan& s : result.scans)
      if (s.path == path) already = s.name;
    if (!already.empty()) {
      Error e = MakeError(ErrorCode::kInvalidArgument,
                          "'" + path.string() + "' is already in the project (scan '" + already + "'); not added again");
      if (refuse(e)) continue;
      return e;
    }
    SubProgress sub(progress, double(f) / scan_files.size(), double(f + 1) / scan_files.size());
    // Through the project's binary scan cache: the first read stores the scans there, so that
    // opening or registering the project later reads them back instead of parsing the file again.
    Expected<std::vector<Scan>> scans = io::ReadScanFileCached(path, ProjectCacheDir(project), sub, cancel);
    if (!scans) {
      if (refuse(scans.error())) continue;
      return scans.error();
    }
    const std::size_t first_new = result.scans.size();
    const std::set<std::string> names_before = names;
    bool bad_file = false;
    for (std::size_t k = 0; k < scans->size() && !bad_file; ++k) {
      const Scan& scan = (*scans)[k];
      if (scan.CountValid() == 0) {
        Error e = MakeError(ErrorCode::kInvalidArgument, "scan '" + scan.name + "' in '" + path.string() +
                                                             "' has no valid point; remove it from the list");
        if (!refuse(e)) return e;
        bad_file = true;  // the file's other scans go too: it is added whole or not at all
        continue;
      }
      io::ProjectScan ps;
      ps.name = scan.name;
      for (int n = 2; !names.insert(ps.name).second; ++n) ps.name = scan.name + "_" + std::to_string(n);
      ps.path = path;
      ps.index_in_file = static_cast<int>(k);
      ps.world_from_scan = scan.world_from_scan;
      // A registered pose in the file's header (another program's registration) is used as it is.
      ps.registered = ps.imported_pose = !scan.world_from_scan.matrix().isIdentity(1e-12);
      if (ps.imported_pose) ps.file_up = scan.world_from_scan.linear().transpose() * Eigen::Vector3d::UnitZ();
      ps.reference_world_from_scan = scan.reference_world_from_scan;
      result.scans.push_back(std::move(ps));
    }
    if (bad_file) {
      result.scans.resize(first_new);
      names = names_before;
    }
  }
  // A single scan is its own frame: nothing to register it to, and it can be merged and exported.
  if (result.scans.size() == 1) result.scans[0].registered = true;
  project = std::move(result);
  return Status::Ok();
}

Expected<CreatedProject> CreateProject(const std::filesystem::path& project_path, const CreateProjectOptions& options,
                                       ProgressSink& progress, const CancelToken& cancel) {
  if (options.scan_files.empty()) {
    return MakeError(ErrorCode::kInvalidArgument, "a project needs at least one scan file");
  }
  io::Project project;
  project.file = std::filesystem::absolute(project_path);
  std::vector<std::string> skipped;
  if (Status s = AppendScanFiles(project, options.scan_files, progress, cancel,
                                 options.skip_unreadable ? &skipped : nullptr);
      !s)
    return s.error();
  if (project.scans.empty()) {
    std::string all;
    for (const std::string& why : skipped) all += "\n  " + why;
    return MakeError(ErrorCode::kInvalidArgument, "no scan file could be added:" + all);
  }
  for (const auto& [file, reference] :
       {std::make_pair(options.poses, false), std::make_pair(options.reference_poses, true)}) {
    if (!file) continue;
    Expected<std::vector<io::NamedPose>> poses = ReadPoseFile(*file);
    if (!poses) return poses.error();
    if (Status s = ApplyPoses(*file, *poses, reference, project); !s) return s.error();
  }
  if (options.control) {
    if (Status s = ImportControl(*options.control, options.check_points, project); !s) return s.error();
  } else if (!options.check_points.empty()) {
    return MakeError(ErrorCode::kInvalidArgument, "check points need a control file (--control FILE)");
  }
  if (Status s = io::SaveProject(project, project_path, &project.disk_digest); !s) return s.error();
  return CreatedProject{std::move(project), std::move(skipped)};
}

Expected<io::Project> WriteSimulatedProject(const SimulatedProjectOptions& options, const std::filesystem::path& dir,
                                            ProgressSink& progress, const CancelToken& cancel, ScanFileFormat format) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    return MakeError(ErrorCode::kIoError, "cannot create folder '" + dir.string() + "': " + ec.message());
  }
  io::Project project;
  const std::filesystem::path project_path = std::filesystem::absolute(dir / "project.scanreg.json");
  project.file = project_path;
  OutputSet written;  // the scans and the project: a project without its scans is not left behind
  // Each scan is written as soon as it is simulated: one scan in memory at a time.
  const Status simulated = SimulateProjectScans(
      options,
      [&](Scan&& scan, std::vector<std::uint8_t>&&) -> Status {
        const bool e57 = format == ScanFileFormat::kE57;
        const std::filesystem::path file = project_path.parent_path() / (scan.name + (e57 ? ".e57" : ".ptx"));
        written.Track(file);
        NullProgress quiet;
        if (Status s = e57 ? io::WriteE57(file, {scan}, quiet, cancel) : io::WritePtx(file, {scan}, quiet, cancel); !s)
          return s;
        io::ProjectScan ps;
        ps.name = scan.name;
        ps.path = file;
        ps.world_from_scan = scan.world_from_scan;
        ps.reference_world_from_scan = scan.reference_world_from_scan;
        project.scans.push_back(std::move(ps));
        return Status::Ok();
      },
      progress, cancel);
  if (!simulated) return written.Failed(simulated.error());
  project.settings["simulated.stations"] = std::to_string(options.stations);
  project.settings["simulated.seed"] = std::to_string(options.seed);
  project.settings["simulated.size"] =
      std::to_string(options.scanner.cols) + "x" + std::to_string(options.scanner.rows);
  project.settings["simulated.noise_m"] = std::to_string(options.scanner.range_noise_m);
  // The survey's control of the sphere targets (as a total station measured them), for
  // `register --control`; not attached to the project, as a surveyor's own file would not be.
  const std::vector<SimulatedTarget> targets = SimulatedTargets(options);
  if (!targets.empty()) {
    std::vector<io::ControlPoint> control;
    for (const SimulatedTarget& t : targets) {
      io::ControlPoint c;
      c.name = t.name;
      c.position = t.measured;
      if (options.control_noise_m > 0) c.sigma_m = options.control_noise_m;
      control.push_back(c);
    }
    const std::filesystem::path file = project_path.parent_path() / "control.csv";
    written.Track(file);
    if (Status s = io::WriteControlFile(file, control); !s) return written.Failed(s.error());
  }
  written.Track(project_path);
  if (Status s = io::SaveProject(project, project_path, &project.disk_digest); !s) return written.Failed(s.error());
  written.Complete();
  return project;
}

}  // namespace scanreg::pipeline
