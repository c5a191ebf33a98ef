// Survey control points: the coordinates a total station or GNSS gave the project's targets, in
// the project coordinate system (national grid, UTM, a site grid). metres, double.
//
// Control file (CSV, one point per line):
//   name, E, N, H [, sigma_m]
// Fields are separated by commas, semicolons, tabs or spaces. Lines starting with '#' and blank
// lines are skipped; a first line whose second field is not a number is a header and skipped
// ("Point,Easting,Northing,Height,Sigma"). sigma_m is the point's standard deviation in metres
// (optional: the adjustment's default is then used). Names are unique; a name holding a separator
// is quoted ("CP 1").
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io {

struct ControlPoint {
  std::string name;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // E, N, H
  std::optional<double> sigma_m;
  // A check point: not used to place the project, only compared with it (its check residual).
  bool check = false;
};

// Errors name the file and line: a missing field, a number that is not finite, a sigma outside
// (0, 10] m, a name given twice, an empty file, a file over 64 MB, not a regular file.
Expected<std::vector<ControlPoint>> ReadControlFile(const std::filesystem::path& path);

// Makes the named points check points; an error names a name that is no control point.
Status MarkCheckPoints(const std::vector<std::string>& names, std::vector<ControlPoint>* points);

// Writes name,E,N,H,sigma_m with a header line (atomic); numbers read back exactly.
Status WriteControlFile(const std::filesystem::path& path, const std::vector<ControlPoint>& points);

}  // namespace scanreg::io
