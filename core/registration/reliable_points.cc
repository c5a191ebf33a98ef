#include "core/registration/reliable_points.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace scanreg {
namespace {

constexpr double kPi = 3.14159265358979323846;

double WrapAngle(double a) {
  while (a > kPi) a -= 2.0 * kPi;
  while (a <= -kPi) a += 2.0 * kPi;
  return a;
}

bool SizesAgree(const Scan& scan) {
  const std::size_t n = static_cast<std::size_t>(scan.rows) * scan.cols;
  return scan.rows > 0 && scan.cols > 0 && scan.points.size() == n && scan.reflectance.size() == n &&
         scan.valid.size() == n;
}

}  // namespace

Status ReliabilityOptions::Validate() const {
  if (!std::isfinite(min_reflectance))
    return MakeError(ErrorCode::kInvalidArgument, "reliability: min_reflectance must be a finite number");
  if (!(max_range_std_m > 0.0) || !std::isfinite(max_range_std_m))
    return MakeError(ErrorCode::kInvalidArgument, "reliability: max_range_std_m (t_std) must be > 0 metres, got " +
                                                      std::to_string(max_range_std_m));
  return Status::Ok();
}

bool WrapsAzimuth(const Scan& scan) {
  const auto& az = scan.angles.azimuth;
  if (scan.cols < 3 || static_cast<int>(az.size()) != scan.cols) return false;
  double travel = 0.0;
  for (int c = 0; c + 1 < scan.cols; ++c) travel += std::abs(WrapAngle(double(az[c + 1]) - az[c]));
  const double step = travel / (scan.cols - 1);
  const double gap = std::abs(WrapAngle(double(az[0]) - az[scan.cols - 1]));
  return travel > kPi && gap <= 1.5 * step;
}

std::vector<std::uint8_t> ConfidenceMap(const Scan& scan, const ReliabilityOptions& options) {
  std::vector<std::uint8_t> conf(static_cast<std::size_t>(std::max(scan.rows, 0)) * std::max(scan.cols, 0), 0);
  if (!SizesAgree(scan)) return conf;
  const bool wrap = WrapsAzimuth(scan);
  const double max_var = options.max_range_std_m * options.max_range_std_m;
  std::vector<float> range(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i) range[i] = scan.valid[i] ? scan.points[i].norm() : 0.0f;

  for (int r = 1; r + 1 < scan.rows; ++r) {
    for (int c = 0; c < scan.cols; ++c) {
      if (!wrap && (c == 0 || c + 1 == scan.cols)) continue;
      const std::size_t centre = scan.Index(r, c);
      if (!scan.valid[centre] || !(scan.reflectance[centre] >= options.min_reflectance)) continue;
      double sum = 0.0, sum2 = 0.0;
      bool ok = true;
      for (int dr = -1; dr <= 1 && ok; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int cc = (c + dc + scan.cols) % scan.cols;
          const std::size_t k = scan.Index(r + dr, cc);
          if (!scan.valid[k]) {
            ok = false;
            break;
          }
          sum += range[k];
          sum2 += double(range[k]) * range[k];
        }
      }
      if (!ok) continue;
      const double mean = sum / 9.0;
      const double var = std::max(0.0, sum2 / 9.0 - mean * mean);
      if (var <= max_var) conf[centre] = 1;
    }
  }
  return conf;
}

std::optional<Eigen::Vector3f> InterpolatePoint(const Scan& scan, const std::vector<std::uint8_t>& confidence,
                                                float u, float v) {
  if (!SizesAgree(scan) || !std::isfinite(u) || !std::isfinite(v)) return std::nullopt;
  if (!confidence.empty() && confidence.size() != scan.size()) return std::nullopt;
  const bool wrap = WrapsAzimuth(scan);
  int r0 = static_cast<int>(std::floor(v));
  float fv = v - r0;
  if (r0 == scan.rows - 1 && fv == 0.0f) {  // exactly on the last row
    r0 -= 1;
    fv = 1.0f;
  }
  if (r0 < 0 || r0 + 1 >= scan.rows) return std::nullopt;
  int c0 = static_cast<int>(std::floor(u));
  float fu = u - c0;
  int c1 = c0 + 1;
  if (wrap) {
    if (c0 < -1 || c0 >= scan.cols) return std::nullopt;
    c0 = (c0 + scan.cols) % scan.cols;
    c1 = (c0 + 1) % scan.cols;
  } else {
    if (c0 == scan.cols - 1 && fu == 0.0f) {  // exactly on the last column
      c0 -= 1;
      c1 -= 1;
      fu = 1.0f;
    }
    if (c0 < 0 || c1 >= scan.cols) return std::nullopt;
  }
  const std::size_t idx[4] = {scan.Index(r0, c0), scan.Index(r0, c1), scan.Index(r0 + 1, c0),
                              scan.Index(r0 + 1, c1)};
  for (std::size_t k : idx) {
    if (!scan.valid[k]) return std::nullopt;
    if (!confidence.empty() && !confidence[k]) return std::nullopt;
  }
  const Eigen::Vector3f top = (1.0f - fu) * scan.points[idx[0]] + fu * scan.points[idx[1]];
  const Eigen::Vector3f bottom = (1.0f - fu) * scan.points[idx[2]] + fu * scan.points[idx[3]];
  return Eigen::Vector3f((1.0f - fv) * top + fv * bottom);
}

}  // namespace scanreg
