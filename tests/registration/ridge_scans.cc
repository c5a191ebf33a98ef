#include "tests/registration/ridge_scans.h"

#include <cmath>
#include <limits>
#include <string>

namespace scanreg::testing {

Eigen::Isometry3d RidgeViewPose(const RidgeModel& model, double view_deg, bool about_x) {
  const double a = view_deg * M_PI / 180.0;
  const Eigen::Vector3d o = about_x ? model.distance * Eigen::Vector3d(0.0, std::sin(a), std::cos(a))
                                    : model.distance * Eigen::Vector3d(std::sin(a), 0.0, std::cos(a));
  const Eigen::Vector3d fwd = -o.normalized();
  const Eigen::Vector3d up = about_x ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Matrix3d r;
  r.col(0) = fwd;
  r.col(1) = up.cross(fwd);
  r.col(2) = up;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = r;
  pose.translation() = o;
  return pose;
}

Scan CastRidgeScan(const RidgeModel& model, const Eigen::Isometry3d& world_from_scan, double sigma_m,
                   std::mt19937& rng) {
  const double step = model.spacing / model.distance;
  const int half = static_cast<int>(std::ceil(1.3 * model.half_width / model.spacing));
  const int n = 2 * half + 1;
  Scan scan("ridge", n, n);
  scan.angles.azimuth.resize(n);
  scan.angles.elevation.resize(n);
  for (int i = 0; i < n; ++i) {
    scan.angles.azimuth[i] = static_cast<float>((half - i) * step);  // col 0 on the scanner's left
    scan.angles.elevation[i] = static_cast<float>((half - i) * step);
  }
  std::normal_distribution<double> noise(0.0, sigma_m);
  const Eigen::Vector3d o = world_from_scan.translation();
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double az = scan.angles.azimuth[c], el = scan.angles.elevation[r];
      const Eigen::Vector3d ds(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = world_from_scan.linear() * ds;
      double best = std::numeric_limits<double>::infinity();
      for (int sx = -1; sx <= 1; sx += 2) {
        for (int sy = -1; sy <= 1; sy += 2) {
          const Eigen::Vector3d nrm(model.slope_x * sx, model.slope_y * sy, 1.0);  // plane n . p = 0
          const double den = nrm.dot(d);
          if (std::abs(den) < 1e-12) continue;
          const double lambda = -nrm.dot(o) / den;
          if (!(lambda > 0) || lambda >= best) continue;
          const Eigen::Vector3d p = o + lambda * d;
          if (std::abs(p.x()) > model.half_width || std::abs(p.y()) > model.half_width) continue;
          if (p.x() * sx < -1e-12 || (model.slope_y != 0 && p.y() * sy < -1e-12)) continue;
          best = lambda;
        }
      }
      if (!std::isfinite(best)) continue;
      const double range = best + noise(rng);
      scan.Set(r, c, (range * ds).cast<float>(), 1.0f);
    }
  }
  scan.world_from_scan = world_from_scan;
  scan.reference_world_from_scan = world_from_scan;
  return scan;
}

}  // namespace scanreg::testing
