// Scans of known geometry for the merge tests: analytic spheres and planes seen from given
// scanner positions (a small panoramic window aimed at the object, noise along the line of sight),
// and boxes through the simulator.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg::test {

// Range along unit ray dir from origin to the first hit, if any.
using RayCast = std::function<std::optional<double>(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir)>;

// A rows x cols window of azimuths/elevations centred on the direction to `target`, spanning
// half_angle_rad either way (half_elevation_rad vertically when given); scanner upright (identity rotation) at `eye`; noise sigma along the
// line of sight. world_from_scan is set (the scan is registered).
inline Scan MakeWindowScan(const RayCast& cast, const Eigen::Vector3d& eye, const Eigen::Vector3d& target, int rows,
                           int cols, double half_angle_rad, double sigma, unsigned seed, const std::string& name,
                           double half_elevation_rad = 0.0) {
  const double half_el = half_elevation_rad > 0.0 ? half_elevation_rad : half_angle_rad;
  Scan scan(name, rows, cols);
  const Eigen::Vector3d d = (target - eye).normalized();
  const double az0 = std::atan2(d.y(), d.x()), el0 = std::atan2(d.z(), std::hypot(d.x(), d.y()));
  scan.angles.azimuth.resize(cols);
  scan.angles.elevation.resize(rows);
  for (int c = 0; c < cols; ++c) scan.angles.azimuth[c] = float(az0 - half_angle_rad + (c + 0.5) * 2 * half_angle_rad / cols);
  for (int r = 0; r < rows; ++r) scan.angles.elevation[r] = float(el0 + half_el - (r + 0.5) * 2 * half_el / rows);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double az = scan.angles.azimuth[c], el = scan.angles.elevation[r];
      const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const auto t = cast(eye, dir);
      if (!t) continue;
      scan.Set(r, c, (dir * (*t + noise(rng))).cast<float>(), 0.5f);
    }
  }
  scan.world_from_scan = Eigen::Isometry3d(Eigen::Translation3d(eye));
  scan.reference_world_from_scan = scan.world_from_scan;
  return scan;
}

inline RayCast SphereCaster(const Eigen::Vector3d& center, double radius) {
  return [=](const Eigen::Vector3d& o, const Eigen::Vector3d& d) -> std::optional<double> {
    const Eigen::Vector3d oc = o - center;
    const double b = oc.dot(d), c = oc.squaredNorm() - radius * radius, disc = b * b - c;
    if (disc < 0) return std::nullopt;
    const double t = -b - std::sqrt(disc);
    if (t <= 0) return std::nullopt;
    return t;
  };
}

// Views from the 6 axis directions and the 8 cube corners at `distance` from the centre.
inline std::vector<Eigen::Vector3d> AllAroundEyes(const Eigen::Vector3d& center, double distance) {
  std::vector<Eigen::Vector3d> eyes;
  for (int a = 0; a < 3; ++a) {
    for (int s : {-1, 1}) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[a] = s;
      eyes.push_back(center + distance * e);
    }
  }
  for (int i = 0; i < 8; ++i) {
    eyes.push_back(center + distance * Eigen::Vector3d(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1).normalized());
  }
  return eyes;
}

}  // namespace scanreg::test
