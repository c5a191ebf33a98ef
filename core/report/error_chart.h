// Errors against the reference poses per scan, in the manner of W's figure 6 (absolute position
// error after coarse and after fine registration, per scan): two bar panels, position (mm) and
// angle (degrees), a light bar for coarse and a dark bar for fine, scans in project order.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/pipeline/register_project.h"

namespace scanreg::report {

// names and errors: one per scan. Scans without an error (unregistered, no reference) are
// marked "n/a".
cv::Mat DrawReferenceErrorChart(const std::vector<std::string>& names,
                                const std::vector<pipeline::ReferenceError>& errors);

}  // namespace scanreg::report
