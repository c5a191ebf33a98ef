#include "core/registration/consistency.h"

#include <algorithm>
#include <cmath>

namespace scanreg {

std::vector<int> ConsistentIndices(const std::vector<Correspondence3d>& correspondences,
                                   const Eigen::Isometry3d& parent_from_child, double threshold_m,
                                   double angular_rad) {
  std::vector<int> out;
  const double a2 = angular_rad * angular_rad;
  for (std::size_t i = 0; i < correspondences.size(); ++i) {
    const auto& c = correspondences[i];
    const double t = c.tolerance_m > 0.0 ? c.tolerance_m : threshold_m;
    const double t2 = t * t + a2 * c.child.squaredNorm();
    if ((c.parent - parent_from_child * c.child).squaredNorm() <= t2) out.push_back(static_cast<int>(i));
  }
  return out;
}

double ConsistencyThreshold(double range_sigma_m, double k, double floor_m) {
  return std::max(k * std::sqrt(2.0) * std::abs(range_sigma_m), floor_m);
}

}  // namespace scanreg
