// The georeferencing parts of the CLI (issue 15): importing control into a project (`new` and
// `register --control FILE --check NAME`) and the residual table `register` prints.
#pragma once

#include <nlohmann/json.hpp>

#include "app/cli_args.h"
#include "core/common/expected.h"
#include "core/io/project.h"
#include "core/pipeline/register_project.h"

namespace scanreg::cli {

// The --control and --check options of `new` and `register`.
std::vector<OptionSpec> ControlOptions();

// --control FILE replaces the project's control points with the file's; --check NAME (repeatable)
// makes a control point a check point (compared, not used). Errors name the file or the point.
Status ImportControl(const Args& args, io::Project* project);

// The control table after a registration of a project with control points (nothing without).
void PrintGeoref(const io::Project& project, const pipeline::ProjectRegistration& result);
nlohmann::json GeorefJson(const io::Project& project, const pipeline::ProjectRegistration& result);

}  // namespace scanreg::cli
