// The report's georeferencing section (issue 15): the control residuals a surveyor signs off,
// graded against the tolerance, and the targets each scan contributed.
#pragma once

#include <string>

#include "core/io/project.h"

namespace scanreg::report {

// Empty for a project without control points.
std::string ControlSection(const io::Project& project);

}  // namespace scanreg::report
