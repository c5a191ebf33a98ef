// Loading the scans of a project, with the project's poses applied to them.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"

namespace scanreg::pipeline {

// Reads every scan of the project (each file once), names it as in the project and sets its
// world_from_scan and reference pose from the project. Errors name the scan and its file.
Expected<std::vector<Scan>> LoadProjectScans(const io::Project& project, ProgressSink& progress,
                                             const CancelToken& cancel);

}  // namespace scanreg::pipeline
