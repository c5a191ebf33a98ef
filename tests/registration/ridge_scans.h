// Test/benchmark helper: S §4.1's synthetic range images. A height field of planes through the
// origin, z = -a|x| - b|y| over |x|, |y| <= half_width (b = 0: S's two-plane model, a ridge along
// y), seen by a small perspective range camera (an angular grid, so the scans are ordinary
// organized Scans) from a viewpoint rotated about the y axis; Gaussian noise along each line of
// sight. No dependency on core/simulate.
#pragma once

#include <Eigen/Geometry>
#include <random>

#include "core/geometry/scan.h"

namespace scanreg::testing {

struct RidgeModel {
  double slope_x = std::tan(30.0 * M_PI / 180.0);  // a: each plane tilted 30 deg from the x axis
  double slope_y = 0.0;                             // b: 0 = two planes (ridge along y)
  double half_width = 0.5;                          // S: width 1.0
  double spacing = 0.025;                           // S: vertex interval 0.025 (at the model)
  double distance = 2.0;                            // camera to origin
};

// The sensor's pose for a viewing direction tilted view_deg from +z (looking at the origin) about
// the world y axis (the ridge; scanner z = world y), or about the world x axis when about_x
// (tilting along the ridge; scanner z = world x).
Eigen::Isometry3d RidgeViewPose(const RidgeModel& model, double view_deg, bool about_x = false);

// One range image from world_from_scan; sigma_m noise along each line of sight (seeded rng).
Scan CastRidgeScan(const RidgeModel& model, const Eigen::Isometry3d& world_from_scan, double sigma_m,
                   std::mt19937& rng);

}  // namespace scanreg::testing
