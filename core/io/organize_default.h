// Organizing an unorganized cloud when the file gives no grid: the angular step is chosen from
// the point density, so that most points keep a cell of their own.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Points are in the scanner frame (scanner at the origin). The step is the mean angular spacing
// of the points over the occupied part of the (azimuth, elevation) plane, divided by
// kOversampling. `source` names the file in error messages.
Expected<Scan> OrganizeCloudByDensity(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                                      std::string name, const std::string& source);

// Exposed for tests: the angular step (radians) OrganizeCloudByDensity would use; 0 when the
// cloud has no usable point.
double DensityAngularStep(const std::vector<Eigen::Vector3f>& points);

}  // namespace scanreg::io
