// Organizing an unorganized cloud into a panoramic grid by spherical projection around the
// scanner origin (SPEC §1).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg {

struct OrganizeOptions {
  double azimuth_step_rad = 0.12 * M_PI / 180.0;    // column spacing (W: 0.12 deg)
  double elevation_step_rad = 0.12 * M_PI / 180.0;  // row spacing
  // Elevation range of the grid; when min >= max, it is taken from the data.
  double elevation_min_rad = 0.0;
  double elevation_max_rad = 0.0;
  Status Validate() const;
};

// points are in the scanner frame (subtract the scanner origin first). When two points fall in
// one cell, the nearer one (the first return) is kept. Row 0 is the highest elevation; column 0
// starts at azimuth -pi. Non-finite points are skipped. reflectance may be empty (then 0.5).
Expected<Scan> OrganizeCloud(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                             const OrganizeOptions& options, std::string name);

}  // namespace scanreg
