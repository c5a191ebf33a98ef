// Creating a project from scan files (scanreg-cli new, the GUI's New project / Add scans) and
// from the simulator (the demo).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/pose_file.h"
#include "core/io/project.h"
#include "core/simulate/project_sim.h"

namespace scanreg::pipeline {

struct CreateProjectOptions {
  std::vector<std::filesystem::path> scan_files;  // PTX (one or more scans each), PLY, PCD
  // Optional pose files (ReadPoseFile); matched to scans by scan name or file name. `poses` become
  // the scans' imported poses (ProjectScan::imported_pose), `reference_poses` the reference.
  std::optional<std::filesystem::path> poses;
  std::optional<std::filesystem::path> reference_poses;
  // Survey control points (io::ReadControlFile) and the names of those that are check points.
  std::optional<std::filesystem::path> control;
  std::vector<std::string> check_points;
  // Files that cannot be added (unreadable, a scan without points, already in the project) are left
  // out and listed in CreatedProject::skipped (the GUI); otherwise the first one is the error (the CLI).
  bool skip_unreadable = false;
};

struct CreatedProject {
  io::Project project;      // as saved (disk_digest set)
  std::vector<std::string> skipped;  // with skip_unreadable: why each file left out was left out
};

// Every pose format `export-poses` writes, by extension: Stanford .conf, poses .json, poses .csv,
// one 4x4 matrix <scan>.txt, or a folder of <scan>.txt files.
Expected<std::vector<io::NamedPose>> ReadPoseFile(const std::filesystem::path& path);

// Reads every scan file (to check it and learn its scans), builds the project and saves it at
// project_path. Scan names are unique (a suffix is added on collision). A scan with no valid
// point is an error naming it. Pose-file entries that match no scan are named in a warning (an
// error when none matches).
Expected<CreatedProject> CreateProject(const std::filesystem::path& project_path, const CreateProjectOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel);

// Reads scan files and appends their scans to `project` (the GUI's Add scans): each scan named
// uniquely within the project (a suffix on collision), its pose from the file (imported when the
// file holds a registered pose; a project of one scan has that scan in place). Each file's points
// are dropped once checked; the project's scan cache keeps them (read them back with
// LoadProjectScans or LoadScanPreviews). A file already in the project is refused
// (not added twice). Without `skipped`, the first file that cannot be added is the error and
// `project` is unchanged; with it, every such file is left out (whole) with its reason listed there
// and the others are added (batch add: one bad file does not stop the rest).
Status AppendScanFiles(io::Project& project, const std::vector<std::filesystem::path>& scan_files,
                       ProgressSink& progress, const CancelToken& cancel, std::vector<std::string>* skipped = nullptr);

enum class ScanFileFormat {
  kPtx,  // text, every cell (the paper's format; ~40 bytes a cell)
  kE57,  // binary, valid cells only (~20 bytes a point): large simulated campaigns on less disk
};

// Simulates a project into `dir`: one PTX or E57 file per station (points in the scanner frame,
// identity pose, as a real unregistered project arrives), written as soon as it is simulated (one
// scan in memory at a time), and `dir/project.scanreg.json` whose reference poses are the true
// poses; with sphere targets also `dir/control.csv` (their measured control coordinates, for
// `register --control`).
Expected<io::Project> WriteSimulatedProject(const SimulatedProjectOptions& options, const std::filesystem::path& dir,
                                            ProgressSink& progress, const CancelToken& cancel,
                                            ScanFileFormat format = ScanFileFormat::kPtx);

}  // namespace scanreg::pipeline
