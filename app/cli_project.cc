// scanreg-cli new / info / link / export-poses.
#include <cmath>
#include <cstdio>

#include "app/cli_commands.h"
#include "app/cli_georef.h"
#include "app/cli_util.h"
#include "core/geometry/transform.h"
#include "core/io/output_paths.h"
#include "core/io/pose_csv.h"
#include "core/io/pose_file.h"
#include "core/io/project_lock.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_edits.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"

namespace scanreg::cli {

int RunNew(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("new", "PROJECT.scanreg.json SCAN... [--poses FILE] [--reference-poses FILE]", argv,
                          {{"poses", true, false,
                            "FILE     imported poses: Stanford .conf, or what export-poses writes (.json, .csv,\n"
                            "                     a 4x4 <scan>.txt or a folder of them); the scans are 'imported'"},
                           {"reference-poses", true, false, "FILE   reference (ground-truth) poses, same formats"},
                           ControlOptions()[0], ControlOptions()[1]},
                          &code);
  if (!args) return code;
  if (args->positional().size() < 2) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "new: give the project file and at least one scan file"));
  }
  pipeline::CreateProjectOptions options;
  for (std::size_t i = 1; i < args->positional().size(); ++i) options.scan_files.emplace_back(args->positional()[i]);
  if (auto p = args->Get("poses")) options.poses = *p;
  if (auto p = args->Get("reference-poses")) options.reference_poses = *p;
  if (auto p = args->Get("control")) options.control = *p;
  options.check_points = args->GetAll("check");
  // A new project never replaces a file: forgetting the project name (`new s01.ptx s02.ptx`) would
  // otherwise turn the first scan into a project file, and an existing project would be lost.
  std::error_code ec;
  if (std::filesystem::exists(std::filesystem::symlink_status(args->positional()[0], ec))) {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "new: '" + args->positional()[0] +
                              "' already exists; give the new project a new name (PROJECT.scanreg.json first, then "
                              "the scan files), or remove the old file first"));
  }
  std::vector<std::filesystem::path> inputs = options.scan_files;
  for (const auto& p : {options.poses, options.reference_poses, options.control})
    if (p) inputs.push_back(*p);
  if (Status s = io::CheckNotAnInput(args->positional()[0], inputs, "new: the project file"); !s) {
    return Fail(s.error());
  }
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  auto project = pipeline::CreateProject(args->positional()[0], options, progress, cancel);
  if (!project) return Fail(project.error());
  std::printf("created %s with %zu scans\n", project->project.file.string().c_str(), project->project.scans.size());
  return 0;
}

int RunLink(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("link", "PROJECT.scanreg.json PARENT CHILD --accept|--reject|--clear", argv,
                          {{"accept", false, false,
                            "                   keep the link as it is in every later registration (a weak link "
                            "whose scan was 'not verified' then places it)"},
                           {"reject", false, false, "                   never use the link"},
                           {"clear", false, false, "                    forget the decision on the link"}},
                          &code);
  if (!args) return code;
  const int chosen = args->Has("accept") + args->Has("reject") + args->Has("clear");
  if (args->positional().size() != 3 || chosen != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "link: give the project, the link's parent and child scans, and one of --accept, --reject, "
                          "--clear"));
  }
  // One writer at a time (a register running on the project would otherwise lose this decision).
  Expected<io::ProjectLock> lock = io::ProjectLock::Acquire(args->positional()[0], "scanreg-cli link");
  if (!lock) return Fail(lock.error());
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  const std::string& parent = args->positional()[1];
  const std::string& child = args->positional()[2];
  const pipeline::LinkDecision decision = args->Has("accept")   ? pipeline::LinkDecision::kAccept
                                          : args->Has("reject") ? pipeline::LinkDecision::kReject
                                                                : pipeline::LinkDecision::kClear;
  if (Status s = pipeline::SetLinkDecision(parent, child, decision, *project); !s) {
    return Fail(MakeError(s.error().code, "link: " + s.error().message));
  }
  if (Status s = io::SaveProject(*project, project->file); !s) return Fail(s.error());
  const char* done = decision == pipeline::LinkDecision::kAccept   ? "accepted"
                     : decision == pipeline::LinkDecision::kReject ? "rejected"
                                                                    : "cleared the decision on";
  std::printf("%s the link %s -> %s in %s; the next register %s\n", done, parent.c_str(), child.c_str(),
              project->file.string().c_str(),
              decision == pipeline::LinkDecision::kAccept   ? "keeps it as it is"
              : decision == pipeline::LinkDecision::kReject ? "never uses it"
                                                            : "judges it on its evidence");
  return 0;
}

int RunInfo(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp("info", "PROJECT.scanreg.json", argv, {}, &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "info: give exactly one project file"));
  }
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  auto scans = pipeline::LoadProjectScans(*project, progress, cancel);
  if (!scans) return Fail(scans.error());
  std::printf("project %s\n%zu scans, %zu links, root %s\n\n", project->file.string().c_str(), scans->size(),
              project->links.size(), project->root ? project->root->c_str() : "(automatic)");
  std::printf("%-12s %-24s %11s %8s %11s  %-12s %10s %10s %10s %8s %s\n", "scan", "file", "size", "valid %", "points",
              "status", "x (m)", "y (m)", "z (m)", "yaw (°)", "reference error");
  // Errors against the reference, relative to the root (the datum of the registration is the root's).
  const std::vector<pipeline::ReferenceError> errors = pipeline::ReferenceErrors(*project);
  for (std::size_t i = 0; i < scans->size(); ++i) {
    const Scan& s = (*scans)[i];
    const io::ProjectScan& ps = project->scans[i];
    const std::size_t valid = s.CountValid();  // the grid's; the points column counts the list's too
    const Eigen::Isometry3d& t = ps.world_from_scan;
    const double yaw = std::atan2(t.linear()(1, 0), t.linear()(0, 0)) * 180.0 / M_PI;
    std::string reference = "-";
    if (i < errors.size() && errors[i].available) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.1f mm, %.4f°", errors[i].position_m * 1000, errors[i].angle_rad * 180 / M_PI);
      reference = buf;
    } else if (ps.reference_world_from_scan) {
      reference = "(has reference)";
    }
    const std::string size = std::to_string(s.cols) + "x" + std::to_string(s.rows);
    std::printf("%-12s %-24s %11s %8.1f %11zu  %-12s %10.3f %10.3f %10.3f %8.2f %s\n", s.name.c_str(),
                ps.path.filename().string().c_str(), size.c_str(), s.size() ? 100.0 * valid / s.size() : 0.0, s.CountPoints(),
                io::PoseStateName(io::ScanPoseState(ps)), t.translation().x(), t.translation().y(), t.translation().z(),
                yaw, reference.c_str());
  }
  return 0;
}

int RunExportPoses(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp(
      "export-poses", "PROJECT.scanreg.json --format json|txt|csv --out PATH", argv,
      {{"format", true, false,
        "json|txt|csv   json: one file of row-major 4x4 world_from_scan; txt: one CloudCompare 4x4 file per scan;\n"
        "                     csv: scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,status (scanner position in the "
        "world;\n"
        "                     R = Rz(heading) Ry(pitch) Rx(roll), heading counter-clockwise from world +x)"},
       {"out", true, false, "PATH     output file (json, csv) or folder (txt)"},
       {"include-unregistered", false, false,
        "       also list the scans that are not registered, with status 'unregistered' and no pose (json, csv);\n"
        "                     by default they are left out (and named on stderr)"}},
      &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "export-poses: give exactly one project file"));
  }
  const std::string format = args->Get("format").value_or("json");
  const auto out = args->Get("out");
  if (format != "json" && format != "txt" && format != "csv") {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "export-poses: --format must be json, txt or csv, not '" + format + "'"));
  }
  if (!out) return Fail(MakeError(ErrorCode::kInvalidArgument, "export-poses: --out PATH is required"));
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  const bool include_unregistered = args->Has("include-unregistered");
  const std::vector<std::filesystem::path> inputs = io::ProjectInputs(*project);
  std::vector<io::NamedPose> poses;
  std::string left_out;
  int unregistered = 0;
  for (const io::ProjectScan& s : project->scans) {
    const io::PoseState state = io::ScanPoseState(s);
    if (!s.registered) {  // unregistered or not verified: no pose to give
      left_out += (unregistered++ ? ", " : "") + s.name;
      if (!include_unregistered || format == "txt") continue;
    }
    poses.push_back({s.name, s.world_from_scan, s.registered ? io::PoseStateName(state) : io::kUnregisteredStatus});
  }
  if (unregistered > 0) {
    const bool flagged = include_unregistered && format != "txt";
    std::fprintf(stderr, "export-poses: %d of %zu scans are not registered (%s): %s\n", unregistered,
                 project->scans.size(), left_out.c_str(),
                 flagged ? "written with status 'unregistered' and no pose"
                 : format == "txt"
                     ? "left out; a matrix file cannot say a scan is unregistered"
                     : "left out; --include-unregistered lists them with status 'unregistered' and no pose");
  }
  // The file, or each matrix file of the folder, must not be an input.
  if (Status s = io::CheckNotAnInput(*out, inputs, "export-poses: --out"); !s) return Fail(s.error());
  for (const io::NamedPose& p : poses) {
    if (format != "txt") break;
    const std::filesystem::path file = std::filesystem::path(*out) / (p.scan + ".txt");
    if (Status s = io::CheckNotAnInput(file, inputs, "export-poses: --out"); !s) return Fail(s.error());
  }
  if (format == "json" || format == "csv") {
    Status written = format == "json" ? io::WritePosesJson(*out, poses) : io::WritePosesCsv(*out, poses);
    if (!written) return Fail(written.error());
    std::printf("wrote %zu poses to %s\n", poses.size(), out->c_str());
    return 0;
  }
  std::error_code ec;
  std::filesystem::create_directories(*out, ec);
  if (ec)
    return Fail(MakeError(ErrorCode::kIoError, "export-poses: cannot create folder '" + *out + "': " + ec.message()));
  for (const io::NamedPose& p : poses) {
    if (Status st = io::WriteMatrixTxt(std::filesystem::path(*out) / (p.scan + ".txt"), p.world_from_scan); !st) {
      return Fail(st.error());
    }
  }
  std::printf("wrote %zu matrix files to %s\n", poses.size(), out->c_str());
  return 0;
}

}  // namespace scanreg::cli
