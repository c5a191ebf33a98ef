// Loading the scans of a project, with the project's poses applied to them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"

namespace scanreg::pipeline {

// The folder of the project's caches (binary scans, features): ".scanreg-cache" beside the
// project file; empty (no cache) for a project never saved.
std::filesystem::path ProjectCacheDir(const io::Project& project);

// Reads every scan of the project (each file once, from the binary scan cache when it holds the
// file's content: io::ReadScanFileCached), names it as in the project and sets its
// world_from_scan and reference pose from the project. Errors name the scan and its file (a
// missing file: how to relink it). which: only these scans (by index, in this order); empty: all.
Expected<std::vector<Scan>> LoadProjectScans(const io::Project& project, ProgressSink& progress,
                                             const CancelToken& cancel, std::vector<int> which = {});

// Relinking scans whose files moved (issue 14, item 6).
// The scans whose file is not where the project says, by name.
std::vector<std::string> MissingScanFiles(const io::Project& project);
// Looks for each missing file by its file name in `folder`; the scans found there get that path.
// Returns how many scans were relinked.
int RelinkFromFolder(io::Project& project, const std::filesystem::path& folder);
// Points `scan` to `file` after checking that the file holds it: a scan at the same index and, when
// `current` (the scan as loaded) is given, with the same grid (rows x cols). Returns the scan read
// (named, posed as in the project). Errors name the file and what differs; the project is unchanged
// on error.
Expected<Scan> RelinkScan(io::Project& project, const std::string& scan, const std::filesystem::path& file,
                          const Scan* current, ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::pipeline
