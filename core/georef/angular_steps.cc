#include "core/georef/angular_steps.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace scanreg::georef {

void AngularSteps(const Scan& scan, double* dc, double* dr) {
  std::vector<double> c, r;
  const int row_stride = std::max(1, scan.rows / 64), col_stride = std::max(1, scan.cols / 256);
  auto angle = [&](int r0, int c0, int r1, int c1) {
    const Eigen::Vector3d a = scan.Point(r0, c0).cast<double>().normalized(), b = scan.Point(r1, c1).cast<double>().normalized();
    return std::atan2(a.cross(b).norm(), a.dot(b));
  };
  for (int row = 0; row + 1 < scan.rows; row += row_stride) {
    for (int col = 0; col + 1 < scan.cols; col += col_stride) {
      if (!scan.IsValid(row, col) || scan.Point(row, col).norm() < 1e-6) continue;
      if (scan.IsValid(row, col + 1) && scan.Point(row, col + 1).norm() > 1e-6) c.push_back(angle(row, col, row, col + 1));
      if (scan.IsValid(row + 1, col) && scan.Point(row + 1, col).norm() > 1e-6) r.push_back(angle(row, col, row + 1, col));
    }
  }
  auto median = [](std::vector<double>& v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  *dc = median(c);
  *dr = median(r);
}

}  // namespace scanreg::georef
