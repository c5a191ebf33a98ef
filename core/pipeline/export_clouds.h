// Exporting a project's registered scans as point-cloud files, one file per scan, with the
// registered pose either kept in the file's header (points stay in the scanner frame; PTX/E57/PLY
// all carry a pose) or applied to the points (world coordinates, identity header pose). The CLI's
// `export-clouds` and the GUI both run this.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/io/project.h"

namespace scanreg::pipeline {

struct ExportCloudsOptions {
  std::filesystem::path dir;   // output folder, created when missing
  std::string format = "ptx";  // ptx | e57 | ply: the file extension (written by io::WriteScanFile)
  // false: points in the scanner frame, world_from_scan in the header (lossless, re-registrable);
  // true: points in world coordinates (float: keep coordinates near the origin), identity header.
  bool apply_poses = false;

  Status Validate() const;
};

struct ExportedScan {
  std::string name;
  std::filesystem::path file;  // empty when skipped
  std::size_t points = 0;      // valid points written
  std::string skipped;         // why the scan was not written (unregistered)
};

// Writes dir/<scan name>.<format> for every registered scan, reading each scan file once and
// keeping only the scans still to be written in memory. Unregistered scans are skipped (listed
// with the reason). Errors: bad options, no registered scan, a file that cannot be read or
// written (naming it), cancelled.
Expected<std::vector<ExportedScan>> ExportClouds(const io::Project& project, const ExportCloudsOptions& options,
                                                 ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::pipeline
