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
  std::string format = "ptx";  // ptx | e57 | ply | las: the file extension
  // PTX and E57 (their readers apply the header pose): false: points in the scanner frame,
  // world_from_scan in the header (lossless, re-registrable); true: points in world coordinates
  // as floats (a warning names each scan rounded by more than 0.1 mm), identity header.
  // PLY and LAS always hold world coordinates, exactly (WorldFormat): PLY as doubles with the pose
  // and grid kept for scanreg (io::WritePly), LAS 1.4 at 0.1 mm (io::WriteLas, point source ID =
  // the scan's number in the project, from 1).
  bool apply_poses = false;

  Status Validate() const;
};

// Formats whose points are always world coordinates in double precision (ply, las).
bool WorldFormat(const std::string& format);

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
