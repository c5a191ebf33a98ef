#include "core/geometry/scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scanreg {

Scan::Scan(std::string scan_name, int num_rows, int num_cols)
    : name(std::move(scan_name)),
      rows(num_rows),
      cols(num_cols),
      points(static_cast<std::size_t>(num_rows) * num_cols, Eigen::Vector3f::Zero()),
      reflectance(static_cast<std::size_t>(num_rows) * num_cols, 0.0f),
      valid(static_cast<std::size_t>(num_rows) * num_cols, 0) {}

Rgb ToRgb(double red, double green, double blue) {
  const auto channel = [](double v) {
    return static_cast<std::uint8_t>(std::clamp(std::isfinite(v) ? v : 0.0, 0.0, 255.0) + 0.5);
  };
  return {channel(red), channel(green), channel(blue)};
}

void Scan::Set(int row, int col, const Eigen::Vector3f& p, float refl) {
  const std::size_t i = Index(row, col);
  points[i] = p;
  reflectance[i] = refl;
  valid[i] = 1;
}

void Scan::Clear(int row, int col) {
  const std::size_t i = Index(row, col);
  points[i].setZero();
  reflectance[i] = 0.0f;
  valid[i] = 0;
  if (HasColour()) colour[i] = Rgb{0, 0, 0};
  if (HasTime()) time[i] = 0.0;
  if (HasSensor()) sensor[i].setZero();
}

void Scan::AddColour() {
  colour.assign(points.size(), Rgb{0, 0, 0});
  list_colour.assign(list_points.size(), Rgb{0, 0, 0});
}

void Scan::AddTime() {
  time.assign(points.size(), 0.0);
  list_time.assign(list_points.size(), 0.0);
}

void Scan::AddSensor() {
  sensor.assign(points.size(), Eigen::Vector3f::Zero());
  list_sensor.assign(list_points.size(), Eigen::Vector3f::Zero());
}

bool SensorsSpread(const std::vector<Eigen::Vector3f>& sensor, double tolerance_m) {
  for (const Eigen::Vector3f& s : sensor)
    if ((s - sensor.front()).norm() > tolerance_m) return true;
  return false;
}

std::size_t Scan::CountValid() const {
  return static_cast<std::size_t>(std::count(valid.begin(), valid.end(), std::uint8_t{1}));
}

Eigen::Vector3f Scan::LineOfSight(int row, int col) const {
  if (!angles.empty()) {
    const float az = angles.azimuth[col];
    const float el = angles.elevation[row];
    return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }
  const Eigen::Vector3f& p = Point(row, col);
  const float n = p.norm();
  return n > 0.0f ? Eigen::Vector3f(p / n) : Eigen::Vector3f::Zero();
}

Status Scan::Validate() const {
  const std::size_t n = static_cast<std::size_t>(rows) * cols;
  if (rows < 0 || cols < 0 || points.size() != n || reflectance.size() != n || valid.size() != n) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "scan '" + name + "': arrays do not match its " + std::to_string(rows) + " x " +
                         std::to_string(cols) + " grid");
  }
  if (!angles.empty() && (angles.azimuth.size() != static_cast<std::size_t>(cols) ||
                          angles.elevation.size() != static_cast<std::size_t>(rows))) {
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "': angular grid does not match its size");
  }
  // With colour, every cell and every listed point has one.
  if (HasColour() && (colour.size() != n || list_colour.size() != list_points.size())) {
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "': its colours and points differ in number");
  }
  if (HasTime() && (time.size() != n || list_time.size() != list_points.size())) {
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "': its times and points differ in number");
  }
  if (HasSensor() && (sensor.size() != n || list_sensor.size() != list_points.size())) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "scan '" + name + "': its sensor positions and points differ in number");
  }
  if (list_reflectance.size() != list_points.size()) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "scan '" + name + "': its listed points and their reflectance differ in number");
  }
  for (std::size_t i = 0; i < list_points.size(); ++i) {
    if (!list_points[i].allFinite() || !std::isfinite(list_reflectance[i]) ||
        (!list_time.empty() && !std::isfinite(list_time[i])) || (!list_sensor.empty() && !list_sensor[i].allFinite())) {
      return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "': listed point " + std::to_string(i + 1) +
                                                        " (off the grid) holds a NaN or infinite value");
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (valid[i] && (!points[i].allFinite() || !std::isfinite(reflectance[i]) ||
                     (!time.empty() && !std::isfinite(time[i])) || (!sensor.empty() && !sensor[i].allFinite()))) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "scan '" + name + "': cell " + std::to_string(i / cols) + "," + std::to_string(i % cols) +
                           " holds a NaN or infinite value");
    }
  }
  return Status::Ok();
}

namespace {

float Median(std::vector<float>& v) {
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Fills NaN gaps by linear interpolation between known neighbours (constant at the ends).
bool FillGaps(std::vector<float>& values) {
  std::vector<int> known;
  for (int i = 0; i < static_cast<int>(values.size()); ++i)
    if (std::isfinite(values[i])) known.push_back(i);
  if (known.size() < 2) return false;
  for (int i = 0; i < static_cast<int>(values.size()); ++i) {
    if (std::isfinite(values[i])) continue;
    auto hi = std::lower_bound(known.begin(), known.end(), i);
    if (hi == known.begin()) {
      values[i] = values[known.front()] + (values[known[1]] - values[known[0]]) / (known[1] - known[0]) * (i - known[0]);
    } else if (hi == known.end()) {
      const int a = known[known.size() - 2], b = known.back();
      values[i] = values[b] + (values[b] - values[a]) / (b - a) * (i - b);
    } else {
      const int a = *(hi - 1), b = *hi;
      values[i] = values[a] + (values[b] - values[a]) * float(i - a) / float(b - a);
    }
  }
  return true;
}

}  // namespace

bool EstimateAngularGrid(Scan& scan) {
  if (scan.rows < 2 || scan.cols < 2) return false;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> azimuth(scan.cols, nan), elevation(scan.rows, nan);
  std::vector<float> buffer;
  for (int c = 0; c < scan.cols; ++c) {
    buffer.clear();
    for (int r = 0; r < scan.rows; ++r)
      if (scan.IsValid(r, c)) buffer.push_back(std::atan2(scan.Point(r, c).y(), scan.Point(r, c).x()));
    if (buffer.empty()) continue;
    // Unwrap around the first sample so that columns straddling +-pi get a sensible median.
    for (float& a : buffer) a = buffer[0] + std::remainder(a - buffer[0], float(2 * M_PI));
    azimuth[c] = Median(buffer);
  }
  for (int r = 0; r < scan.rows; ++r) {
    buffer.clear();
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      const Eigen::Vector3f& p = scan.Point(r, c);
      buffer.push_back(std::atan2(p.z(), std::hypot(p.x(), p.y())));
    }
    if (!buffer.empty()) elevation[r] = Median(buffer);
  }
  // Make the azimuth sequence continuous (no 2*pi jumps) before filling gaps.
  float prev = nan;
  for (float& a : azimuth) {
    if (!std::isfinite(a)) continue;
    if (std::isfinite(prev)) a = prev + std::remainder(a - prev, float(2 * M_PI));
    prev = a;
  }
  if (!FillGaps(azimuth) || !FillGaps(elevation)) return false;
  scan.angles.azimuth = std::move(azimuth);
  scan.angles.elevation = std::move(elevation);
  return true;
}

}  // namespace scanreg
