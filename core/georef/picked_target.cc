#include "core/georef/picked_target.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/georef/angular_steps.h"

namespace scanreg::georef {

PickedTarget PickTargetAt(const Scan& scan, int row, int col, int search_cells, const SphereTargetOptions& spheres,
                          const CheckerTargetOptions& checkers) {
  PickedTarget out;
  const Eigen::Vector3d p = scan.Point(row, col).cast<double>();
  out.center = p;
  double dc = 0, dr = 0;
  AngularSteps(scan, &dc, &dr);
  out.sigma_m = std::max(p.norm() * std::max(dc, dr), 0.001);  // a cell at this range
  out.fit = "point";
  if (checkers.Validate()) {
    if (auto board = FitCheckerTargetAt(scan, row, col, search_cells, checkers)) {
      out.center = board->center;
      out.sigma_m = board->sigma_m;
      out.fit = "checker";
      return out;
    }
  }
  if (!spheres.Validate() || !(dc > 0) || !(dr > 0)) return out;
  // A sphere: the cells within 1.2 radii of the clicked point, fitted with the radius held; kept
  // when the fit is as tight as the automatic search asks.
  const double r = spheres.radius_m, range = p.norm();
  const int wc = static_cast<int>(std::ceil(1.5 * r / (range * dc))) + search_cells;
  const int wr = static_cast<int>(std::ceil(1.5 * r / (range * dr))) + search_cells;
  std::vector<Eigen::Vector3d> points;
  for (int rr = std::max(0, row - wr); rr <= std::min(scan.rows - 1, row + wr); ++rr)
    for (int cc = std::max(0, col - wc); cc <= std::min(scan.cols - 1, col + wc); ++cc)
      if (scan.IsValid(rr, cc) && (scan.Point(rr, cc).cast<double>() - p).norm() < 1.2 * r)
        points.push_back(scan.Point(rr, cc).cast<double>());
  if (static_cast<int>(points.size()) < spheres.min_points) return out;
  double rms = 0;
  const Eigen::Vector3d centre = FitSphereCenter(points, r, p + r * p.normalized(), &rms);
  if (!centre.allFinite() || rms > spheres.max_rms_fraction * r || (centre - p).norm() > 1.5 * r) return out;
  out.center = centre;
  out.sigma_m = std::max(rms / std::sqrt(static_cast<double>(points.size())) * 3.0, 1e-4);
  out.fit = "sphere";
  return out;
}

}  // namespace scanreg::georef
