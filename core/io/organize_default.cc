#include "core/io/organize_default.h"

#include <cmath>

#include "core/geometry/organize.h"

namespace scanreg::io {

namespace {
// The grid is finer than the mean spacing so that an irregular pattern loses few points to
// shared cells. Measured on cturtle.pcd (167,198 points): factor 1.0 keeps 69 %, 1.4 keeps 92.5 %,
// 1.5 keeps 95 % (grid 33 % filled), 2.0 keeps 100 % but fills only 20 % of the grid.
constexpr double kOversampling = 1.5;
}  // namespace

double DensityAngularStep(const std::vector<Eigen::Vector3f>& points) {
  std::vector<std::pair<double, double>> dirs;
  dirs.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite() || p.squaredNorm() == 0.0f) continue;
    dirs.emplace_back(std::atan2(double(p.y()), double(p.x())),
                      std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y()))));
  }
  if (dirs.empty()) return 0.0;
  // Occupied area of the (azimuth, elevation) plane on a bin grid; the bin must be coarser than
  // the spacing or a sparse cloud looks smaller than it is, so refine from coarse to fine.
  double bin = 2.0 * M_PI / 180.0;
  double step = bin;
  for (int iter = 0; iter < 4; ++iter) {
    const int nb_az = static_cast<int>(std::ceil(2 * M_PI / bin));
    const int nb_el = static_cast<int>(std::ceil(M_PI / bin)) + 1;
    std::vector<std::uint8_t> occupied(static_cast<std::size_t>(nb_az) * nb_el, 0);
    std::size_t count = 0;
    for (const auto& [az, el] : dirs) {
      const int a = std::min(nb_az - 1, static_cast<int>((az + M_PI) / bin));
      const int e = std::min(nb_el - 1, static_cast<int>((el + M_PI / 2) / bin));
      std::uint8_t& o = occupied[static_cast<std::size_t>(e) * nb_az + a];
      count += o == 0;
      o = 1;
    }
    step = std::sqrt(double(count) * bin * bin / double(dirs.size()));
    // Stop when each bin holds many points on average (the area estimate is then reliable).
    if (bin <= 8 * step && bin >= 4 * step) break;
    bin = std::clamp(6 * step, 1e-4, 2.0 * M_PI / 180.0 * 4);
  }
  return step;
}

Expected<Scan> OrganizeCloudByDensity(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                                      std::string name, const std::string& source) {
  const double spacing = DensityAngularStep(points);
  if (spacing <= 0.0) {
    return MakeError(ErrorCode::kParseError,
                     source +
                         ": the cloud has no finite point away from the origin, so it cannot be organized "
                         "into a scan grid");
  }
  OrganizeOptions options;
  options.azimuth_step_rad = options.elevation_step_rad = std::max(spacing / kOversampling, 2e-6);
  Expected<Scan> scan = OrganizeCloud(points, reflectance, options, std::move(name));
  if (!scan) {
    return MakeError(scan.error().code, source +
                                            ": cannot organize the unorganized cloud around the scanner "
                                            "origin (" +
                                            scan.error().message +
                                            "); is the scanner at the origin of the file's frame?");
  }
  return scan;
}

}  // namespace scanreg::io
