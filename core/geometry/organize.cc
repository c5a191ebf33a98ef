#include "core/geometry/organize.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace scanreg {
namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// A usable input point with its ideal cell.
struct Candidate {
  double offset;        // azimuth from the grid's left edge, radians, in [0, 2 pi)
  float elevation;      // radians
  float range;          // metres
  std::uint32_t index;  // into the input
  int col;              // the cell its direction falls in
};

// A point given a column of its row.
struct Placed {
  int col;
  const Candidate* point;
};

// Two returns along one ray (multi-echo, duplicates) are never spread over two cells.
bool SameRay(const Candidate& a, const Candidate& b, double tolerance_rad) {
  const double daz = (a.offset - b.offset) * std::cos(double(a.elevation));
  const double del = double(a.elevation) - b.elevation;
  return daz * daz + del * del <= tolerance_rad * tolerance_rad;
}

// Moves the run of adjacent placed points that ends the row one column to the left, when the
// column before the run is free and every point of the run stays within max_shift of its own
// cell. Looks at most kMaxRun points back, so a full row is never rescanned.
bool ShiftRunLeft(std::vector<Placed>& placed, int max_shift) {
  constexpr int kMaxRun = 16;
  const int n = static_cast<int>(placed.size());
  for (int j = n - 1; j >= 0 && j >= n - kMaxRun; --j) {
    const int target = placed[j].col - 1;
    if (target < 0 || target < placed[j].point->col - max_shift) return false;
    if (j == 0 || placed[j - 1].col < target) {
      for (int k = j; k < n; ++k) --placed[k].col;
      return true;
    }
  }
  return false;
}

// Places the points of one row, sorted by azimuth, in columns: each takes its own cell when free,
// else the next free cell to the right within max_shift, else the points before it move one
// column left to make room; when nothing works, the nearer of it and its left neighbour keeps the
// cell. The row keeps its azimuth order, so neighbouring cells hold neighbouring directions.
void PlaceRow(const Candidate* begin, const Candidate* end, int cols, int max_shift, double ray_tolerance_rad,
              std::vector<Placed>& placed) {
  placed.clear();
  for (const Candidate* p = begin; p != end; ++p) {
    const int c = p->col;
    if (placed.empty() || c > placed.back().col) {
      placed.push_back({c, p});
      continue;
    }
    // Here c <= last column <= c + max_shift (points arrive in column order).
    const int last_col = placed.back().col;
    if (max_shift > 0 && !SameRay(*placed.back().point, *p, ray_tolerance_rad)) {
      if (last_col + 1 < cols && last_col + 1 <= c + max_shift) {
        placed.push_back({last_col + 1, p});
        continue;
      }
      if (ShiftRunLeft(placed, max_shift)) {
        placed.push_back({last_col, p});
        continue;
      }
    }
    if (p->range < placed.back().point->range) placed.back().point = p;
  }
}

}  // namespace

Status OrganizeOptions::Validate() const {
  const double min_step = 1e-4 * M_PI / 180.0;
  if (!(azimuth_step_rad > min_step && azimuth_step_rad < M_PI) ||
      (row_elevations_rad.empty() && !(elevation_step_rad > min_step && elevation_step_rad < M_PI))) {
    return MakeError(ErrorCode::kInvalidArgument, "organize: angular steps must lie between 0.0001 and 180 degrees");
  }
  if (elevation_min_rad < elevation_max_rad &&
      (elevation_min_rad < -M_PI / 2 - 1e-9 || elevation_max_rad > M_PI / 2 + 1e-9)) {
    return MakeError(ErrorCode::kInvalidArgument, "organize: elevation range must lie within -90..90 degrees");
  }
  if (!std::isfinite(azimuth_start_rad) || !std::isfinite(azimuth_span_rad)) {
    return MakeError(ErrorCode::kInvalidArgument, "organize: the azimuth range must be finite");
  }
  for (std::size_t i = 0; i < row_elevations_rad.size(); ++i) {
    const double e = row_elevations_rad[i];
    if (!(std::abs(e) <= M_PI / 2 + 1e-9) || (i > 0 && !(e < row_elevations_rad[i - 1]))) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "organize: row elevations must decrease strictly and lie within -90..90 degrees");
    }
  }
  if (max_column_shift < 0 || max_column_shift > 16) {
    return MakeError(ErrorCode::kInvalidArgument, "organize: max_column_shift must lie within 0..16 columns");
  }
  return Status::Ok();
}

CloudProjection::CloudProjection(const std::vector<Eigen::Vector3f>& points)
    : points_(&points), el_min_(std::numeric_limits<double>::infinity()), el_max_(-el_min_) {
  dirs_.reserve(points.size());
  for (std::size_t i = 0; i < points.size() && i <= std::numeric_limits<std::uint32_t>::max(); ++i) {
    const Eigen::Vector3f& p = points[i];
    if (!p.allFinite()) continue;
    const float range = p.norm();
    if (range == 0.0f) continue;
    const double el = std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())));
    dirs_.push_back({std::atan2(double(p.y()), double(p.x())), float(el), range, static_cast<std::uint32_t>(i)});
    el_min_ = std::min(el_min_, el);
    el_max_ = std::max(el_max_, el);
  }
  std::sort(dirs_.begin(), dirs_.end(),
            [](const Dir& a, const Dir& b) { return a.az < b.az || (a.az == b.az && a.range < b.range); });
}

Expected<std::size_t> CloudProjection::CountKept(const OrganizeOptions& options) const {
  return Place(options, {}, {}, {}, {}, "cloud", nullptr);
}

Expected<Scan> CloudProjection::Organize(const std::vector<float>& reflectance, const OrganizeOptions& options,
                                         std::string name, const std::vector<Rgb>& colour,
                                         const std::vector<double>& time,
                                         const std::vector<Eigen::Vector3f>& sensor) const {
  Scan scan;
  Expected<std::size_t> kept = Place(options, reflectance, colour, time, sensor, std::move(name), &scan);
  if (!kept) return kept.error();
  scan.grid_from_file = false;  // built here from a list of points
  return scan;
}

Expected<std::size_t> CloudProjection::Place(const OrganizeOptions& options, const std::vector<float>& reflectance,
                                             const std::vector<Rgb>& colour, const std::vector<double>& time,
                                             const std::vector<Eigen::Vector3f>& sensor, std::string name,
                                             Scan* out) const {
  if (Status s = options.Validate(); !s) return s.error();
  if (out && !reflectance.empty() && reflectance.size() != points_->size()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': reflectance and point counts differ");
  }
  if (out && !colour.empty() && colour.size() != points_->size()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': colour and point counts differ");
  }
  if (out && !time.empty() && time.size() != points_->size()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': time and point counts differ");
  }
  if (out && !sensor.empty() && sensor.size() != points_->size()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': sensor position and point counts differ");
  }
  const bool rings = !options.row_elevations_rad.empty();
  double el_min = options.elevation_min_rad, el_max = options.elevation_max_rad;
  if (!rings && el_min >= el_max) {
    if (dirs_.empty()) {
      return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': the cloud has no finite point");
    }
    el_min = el_min_, el_max = el_max_;
  }
  const double az_step = options.azimuth_step_rad, el_step = options.elevation_step_rad;
  const bool full_turn = !(options.azimuth_span_rad > 0.0 && options.azimuth_span_rad < kTwoPi);
  const double span = full_turn ? kTwoPi : options.azimuth_span_rad;
  const int cols = std::max(1, static_cast<int>(std::ceil(span / az_step - 1e-9)));
  const int rows = rings ? static_cast<int>(options.row_elevations_rad.size())
                         : std::max(1, static_cast<int>(std::floor((el_max - el_min) / el_step + 1e-9)) + 1);
  if (static_cast<double>(rows) * cols > 4e8) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': a " + std::to_string(rows) + " x " +
                                                      std::to_string(cols) +
                                                      " grid is too large; choose a coarser angular step");
  }
  if (out) {
    *out = Scan(std::move(name), rows, cols);
    out->angles.azimuth.resize(cols);
    out->angles.elevation.resize(rows);
    for (int c = 0; c < cols; ++c) out->angles.azimuth[c] = float(options.azimuth_start_rad + (c + 0.5) * az_step);
    for (int r = 0; r < rows; ++r)
      out->angles.elevation[r] = float(rings ? options.row_elevations_rad[r] : el_max - r * el_step);
    if (!colour.empty()) out->AddColour();
    if (!time.empty()) out->AddTime();
    if (!sensor.empty()) out->AddSensor();
  }

  // Ring rows: a point belongs to the ring whose elevation is nearest, i.e. between the midpoints.
  std::vector<double> neg_bounds;  // -(midpoint between rows r and r+1), increasing
  if (rings) {
    for (int r = 0; r + 1 < rows; ++r)
      neg_bounds.push_back(-0.5 * (options.row_elevations_rad[r] + options.row_elevations_rad[r + 1]));
  }
  // Visit the points in azimuth order from the grid's left edge (a rotation of the sorted order),
  // so that grouping them by row (a stable counting sort) leaves each row sorted by azimuth.
  const double start = options.azimuth_start_rad - kTwoPi * std::floor((options.azimuth_start_rad + M_PI) / kTwoPi);
  const std::size_t n = dirs_.size();
  const std::size_t first = static_cast<std::size_t>(
      std::lower_bound(dirs_.begin(), dirs_.end(), start, [](const Dir& d, double a) { return d.az < a; }) -
      dirs_.begin());
  auto offset_of = [start](double az) {
    double offset = az - start;
    if (offset < 0.0) offset += kTwoPi;
    return offset < kTwoPi ? offset : 0.0;  // rounding just below a full turn
  };
  std::vector<std::int32_t> row_of(n, -1);  // in visiting order; -1: outside the grid
  std::vector<std::size_t> row_start(static_cast<std::size_t>(rows) + 1, 0);
  for (std::size_t k = 0; k < n; ++k) {
    const Dir& d = dirs_[(first + k) % n];
    int r;
    if (rings) {
      r = static_cast<int>(std::upper_bound(neg_bounds.begin(), neg_bounds.end(), -double(d.el)) - neg_bounds.begin());
    } else {
      r = static_cast<int>(std::lround((el_max - d.el) / el_step));
      if (r < 0 || r >= rows) continue;
    }
    if (!full_turn && offset_of(d.az) >= cols * az_step) continue;  // outside a partial grid
    row_of[k] = r;
    ++row_start[r + 1];
  }
  for (int r = 0; r < rows; ++r) row_start[r + 1] += row_start[r];
  std::vector<Candidate> by_row(row_start[rows]);
  {
    std::vector<std::size_t> next(row_start.begin(), row_start.end() - 1);
    for (std::size_t k = 0; k < n; ++k) {
      if (row_of[k] < 0) continue;
      const Dir& d = dirs_[(first + k) % n];
      const double offset = offset_of(d.az);
      const int c = std::min(cols - 1, static_cast<int>(offset / az_step));
      by_row[next[row_of[k]]++] = {offset, d.el, d.range, d.index, c};
    }
  }
  row_of = std::vector<std::int32_t>();

  const double ray_tolerance = 0.01 * az_step;
  std::vector<std::uint8_t> in_grid(out ? points_->size() : 0, 0);
  std::size_t kept = 0;
  std::vector<Placed> placed;
  for (int r = 0; r < rows; ++r) {
    PlaceRow(by_row.data() + row_start[r], by_row.data() + row_start[r + 1], cols, options.max_column_shift,
             ray_tolerance, placed);
    kept += placed.size();
    if (!out) continue;
    for (const Placed& pl : placed) {
      const std::uint32_t i = pl.point->index;
      out->Set(r, pl.col, (*points_)[i], reflectance.empty() ? 0.5f : reflectance[i]);
      if (!colour.empty()) out->colour[out->Index(r, pl.col)] = colour[i];
      if (!time.empty()) out->time[out->Index(r, pl.col)] = time[i];
      if (!sensor.empty()) out->sensor[out->Index(r, pl.col)] = sensor[i];
      in_grid[i] = 1;
    }
  }
  if (out) {  // every usable point without a cell stays, as a list, in input order
    std::vector<std::uint8_t> usable(points_->size(), 0);
    for (const Dir& d : dirs_) usable[d.index] = 1;
    for (std::size_t i = 0; i < points_->size(); ++i) {
      if (!usable[i] || in_grid[i]) continue;
      out->list_points.push_back((*points_)[i]);
      out->list_reflectance.push_back(reflectance.empty() ? 0.5f : reflectance[i]);
      if (!colour.empty()) out->list_colour.push_back(colour[i]);
      if (!time.empty()) out->list_time.push_back(time[i]);
      if (!sensor.empty()) out->list_sensor.push_back(sensor[i]);
    }
  }
  return kept;
}

Expected<Scan> OrganizeCloud(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                             const OrganizeOptions& options, std::string name, const std::vector<Rgb>& colour,
                             const std::vector<double>& time, const std::vector<Eigen::Vector3f>& sensor) {
  if (points.size() > std::numeric_limits<std::uint32_t>::max()) {
    return MakeError(ErrorCode::kInvalidArgument, "organize '" + name + "': more than 2^32 points");
  }
  return CloudProjection(points).Organize(reflectance, options, std::move(name), colour, time, sensor);
}

}  // namespace scanreg
