// A target the user picks in a scan (issue 15, item 1): a click on a board or a sphere in the
// panorama becomes the target's centre, refined by the same fits the automatic search uses — a
// checkerboard's pattern centre, else a sphere's centre of the project's radius, else the clicked
// point itself (a corner, a survey nail), with a sigma that says which.
#pragma once

#include <Eigen/Core>
#include <string>

#include "core/georef/checker_targets.h"
#include "core/georef/sphere_targets.h"

namespace scanreg::georef {

struct PickedTarget {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // scanner frame, metres
  double sigma_m = 0;
  std::string fit;  // "checker", "sphere" or "point"
};

// (row, col): a cell with a return. search_cells: how far from the click the fits look (cells).
PickedTarget PickTargetAt(const Scan& scan, int row, int col, int search_cells, const SphereTargetOptions& spheres,
                          const CheckerTargetOptions& checkers);

}  // namespace scanreg::georef
