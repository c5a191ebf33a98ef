// 3D consistency check after the coarse pose (W §4.4, SPEC §2 step 8): pairs whose two points do
// not meet in 3D (e.g. matches on periodic façades that fit the 2D model) are dropped.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/registration/correspondence.h"

namespace scanreg {

// Indices (ascending) of the pairs with |parent - parent_from_child * child| <= t, where
// t = sqrt(threshold_m^2 + (angular_rad * |child|)^2): the angular term is keypoint localisation
// (about a pixel of angular_rad) growing with the range; 0 gives W's fixed threshold. A pair with
// its own tolerance (Correspondence3d::tolerance_m > 0) uses it in place of threshold_m.
std::vector<int> ConsistentIndices(const std::vector<Correspondence3d>& correspondences,
                                   const Eigen::Isometry3d& parent_from_child, double threshold_m,
                                   double angular_rad = 0.0);

// Threshold from the scanner's range noise: max(k * sqrt(2) * range_sigma_m, floor_m).
// Each point carries range noise sigma along its line of sight; the difference of two independent
// points has at most sqrt(2) * sigma standard deviation in any direction, so k = 3 keeps ~99.7%
// of true pairs. The floor (metres) covers keypoint localisation and interpolation error that
// does not scale with the range noise (W gives no number; 3 cm ~ a pixel at 15 m and 0.12°).
// Example: sigma = 12 mm (W's scanner) -> 51 mm.
double ConsistencyThreshold(double range_sigma_m, double k = 3.0, double floor_m = 0.03);

}  // namespace scanreg
