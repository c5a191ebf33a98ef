// Georeferencing a registered project (issue 15): the sphere and checkerboard targets of every
// registered scan are found (options.spheres, options.checkers), the user's picked and named targets kept, and the adjustment of
// core/georef/georeference.h places the project on its control points (options.georef). The
// project's poses, targets and residuals are rewritten; RegisterProjectScans runs this whenever
// the project has control points, so the CLI and the GUI georeference the same way. A scan placed
// by hand (io::ProjectScan::manual_pose) keeps its placement relative to the others: it moves with
// the project, and its targets are not used.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/georef/georeference.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"

namespace scanreg::pipeline {

// scans: the project's scans in its order (LoadProjectScans), or a store of them (read one at a
// time). On error the project is unchanged apart from project.georef, which is dropped (its poses
// stay in the registration's frame).
class ScanStore;
Expected<georef::GeorefResult> GeoreferenceProject(io::Project& project, const std::vector<Scan>& scans,
                                                   const RegisterOptions& options, ProgressSink& progress,
                                                   const CancelToken& cancel);
Expected<georef::GeorefResult> GeoreferenceProject(io::Project& project, ScanStore& scans,
                                                   const RegisterOptions& options, ProgressSink& progress,
                                                   const CancelToken& cancel);

// The 3D residual's grade of a control row against the project's tolerance ("green", "orange",
// "red"); "-" for a point that was not found.
std::string ControlGrade(const io::ControlResidualRecord& row, double tolerance_m);

}  // namespace scanreg::pipeline
