#include "core/geometry/organize.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scanreg {

Status OrganizeOptions::Validate() const {
  const double min_step = 1e-4 * M_PI / 180.0;
  if (!(azimuth_step_rad > min_step && azimuth_step_rad < M_PI) ||
      !(elevation_step_rad > min_step && elevation_step_rad < M_PI)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "organize: angular steps must lie between 0.0001 and 180 degrees");
  }
  if (elevation_min_rad < elevation_max_rad &&
      (elevation_min_rad < -M_PI / 2 - 1e-9 || elevation_max_rad > M_PI / 2 + 1e-9)) {
    return MakeError(ErrorCode::kInvalidArgument, "organize: elevation range must lie within -90..90 degrees");
  }
  return Status::Ok();
}

Expected<Scan> OrganizeCloud(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                             const OrganizeOptions& options, std::string name) {
  if (Status s = options.Validate(); !s) return s.error();
  if (!reflectance.empty() && reflectance.size() != points.size()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': reflectance and point counts differ");
  }
  double el_min = options.elevation_min_rad, el_max = options.elevation_max_rad;
  if (el_min >= el_max) {
    el_min = M_PI, el_max = -M_PI;
    for (const auto& p : points) {
      if (!p.allFinite() || p.squaredNorm() == 0.0f) continue;
      const double el = std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
      el_min = std::min(el_min, el);
      el_max = std::max(el_max, el);
    }
    if (el_min > el_max) {
      return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': the cloud has no finite point");
    }
  }
  const int cols = std::max(1, static_cast<int>(std::ceil(2 * M_PI / options.azimuth_step_rad - 1e-9)));
  const int rows = std::max(1, static_cast<int>(std::floor((el_max - el_min) / options.elevation_step_rad + 1e-9)) + 1);
  if (static_cast<double>(rows) * cols > 4e8) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "organize '" + name + "': a " + std::to_string(rows) + " x " + std::to_string(cols) +
                         " grid is too large; choose a coarser angular step");
  }
  Scan scan(std::move(name), rows, cols);
  scan.angles.azimuth.resize(cols);
  scan.angles.elevation.resize(rows);
  for (int c = 0; c < cols; ++c) scan.angles.azimuth[c] = float(-M_PI + (c + 0.5) * options.azimuth_step_rad);
  for (int r = 0; r < rows; ++r) scan.angles.elevation[r] = float(el_max - r * options.elevation_step_rad);

  std::vector<float> best_range(scan.size(), std::numeric_limits<float>::infinity());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!p.allFinite()) continue;
    const float range = p.norm();
    if (range == 0.0f) continue;
    const double az = std::atan2(double(p.y()), double(p.x()));
    const double el = std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
    const int c = std::clamp(static_cast<int>(std::floor((az + M_PI) / options.azimuth_step_rad)), 0, cols - 1);
    const int r = static_cast<int>(std::lround((el_max - el) / options.elevation_step_rad));
    if (r < 0 || r >= rows) continue;
    const std::size_t k = scan.Index(r, c);
    if (range >= best_range[k]) continue;
    best_range[k] = range;
    scan.Set(r, c, p, reflectance.empty() ? 0.5f : reflectance[i]);
  }
  return scan;
}

}  // namespace scanreg
