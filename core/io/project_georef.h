// The georeferencing part of the project file (core/io/georef_records.h) as JSON:
//   "control": [{"name", "e", "n", "h", "sigma_m"?, "check"?}],
//   "targets": [{"scan", "name", "named_by_user"?, "kind", "center": [x, y, z], "sigma_m", "rms_m", "points", "residual_m"}],
//   "georef": {"rms_m", "used", "targets", "tolerance_m", "control": [{"name", "role", "delta": [dE, dN, dH], "leave_one_out_m", "observations"}]}
// Numbers are written so that they read back exactly (coordinates of thousands of km keep 0.1 mm).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/common/expected.h"
#include "core/io/project.h"

namespace scanreg::io {

// Adds the georeferencing keys (only those with content) to the project's JSON.
void GeorefToJson(const Project& project, nlohmann::json* j);
// Reads them into project (whose scans are already read): errors name the project (`where`), the
// entry and what is wrong (a target naming no scan, a control name given twice, a number not finite).
Status GeorefFromJson(const nlohmann::json& j, const std::string& where, Project* project);

}  // namespace scanreg::io
