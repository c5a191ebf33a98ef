#include "core/io/organize_default.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <optional>
#include <set>
#include <utility>

#include "core/common/log.h"

namespace scanreg::io {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;
// The grid never has more cells than this per usable point (memory stays bounded for any cloud).
constexpr double kMaxCellsPerPoint = 4.0;
// The coarsest candidate grid that keeps this fraction of the points is taken.
constexpr double kTargetKept = 0.995;
// A ring grid is taken when it keeps this fraction (else uniform grids are tried too); of its
// refinements, the coarsest within kRingsNearlyAsGood of the best.
constexpr double kRingsKept = 0.99;
constexpr double kRingsNearlyAsGood = 0.005;
// How far a point may move along its row when its cell is taken: to the adjacent column for
// rings (the columns follow the data's own azimuth step), two columns in a uniform grid finer
// than the point spacing (two cells there are about one point spacing).
constexpr int kRingColumnShift = 1;
constexpr int kUniformColumnShift = 2;

// Candidate grid steps: the data's spacing divided by these factors.
constexpr double kRefinements[] = {1.0, 1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 6.0};

struct Direction {
  double az;  // radians, atan2(y, x)
  double el;  // radians, atan2(z, |xy|)
};

std::vector<Direction> Directions(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Direction> dirs;
  dirs.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite() || p.squaredNorm() == 0.0f) continue;
    dirs.push_back({std::atan2(double(p.y()), double(p.x())),
                    std::atan2(double(p.z()), std::hypot(double(p.x()), double(p.y())))});
  }
  return dirs;
}

// Mean angular spacing of the points over the occupied part of the (azimuth, elevation) plane.
double DensityStep(const std::vector<Direction>& dirs) {
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
    for (const auto& d : dirs) {
      const int a = std::min(nb_az - 1, static_cast<int>((d.az + M_PI) / bin));
      const int e = std::min(nb_el - 1, static_cast<int>((d.el + M_PI / 2) / bin));
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

// Median of the values above `floor` (reorders v); 0 when there is none.
double MedianAbove(std::vector<double>& v, double floor) {
  v.erase(std::remove_if(v.begin(), v.end(), [floor](double x) { return !(x > floor); }), v.end());
  if (v.empty()) return 0.0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Median azimuth step between neighbouring points of the same group (ring or elevation band):
// `keyed` holds (group, azimuth) and is sorted here. Repeated directions (multi-echo) are ignored.
double MedianAzimuthStep(std::vector<std::pair<int, double>>& keyed) {
  std::sort(keyed.begin(), keyed.end());
  std::vector<double> steps;
  steps.reserve(keyed.size());
  for (std::size_t i = 1; i < keyed.size(); ++i)
    if (keyed[i].first == keyed[i - 1].first) steps.push_back(keyed[i].second - keyed[i - 1].second);
  return MedianAbove(steps, 1e-7);
}

// Elevations of the laser rings (or scan rows), highest first, when the elevations form
// well-separated clusters: split the sorted elevations where neighbours are more than a few mean
// gaps apart; the clusters holding >= 2 % of the largest one's points are rings when each gap
// between them is at least half the wider one's width. Smaller clusters are rings too when far
// from every ring, else stray returns that go to the nearest ring; at most 1 % of the points may
// be strays. Empty when the elevations do not form rings.
std::vector<double> FindRings(std::vector<double> el) {
  std::sort(el.begin(), el.end());
  const std::size_t n = el.size();
  if (n < 64) return {};
  const double range = el.back() - el.front();
  if (!(range > 0.0)) return {};
  const double mean_gap = range / double(n - 1);
  for (const double factor : {4.0, 16.0, 64.0}) {
    const double threshold = factor * mean_gap;
    std::vector<std::pair<std::size_t, std::size_t>> clusters;  // [begin, end) in el
    std::size_t begin = 0, largest = 0;
    for (std::size_t i = 1; i <= n; ++i) {
      if (i < n && el[i] - el[i - 1] <= threshold) continue;
      clusters.emplace_back(begin, i);
      largest = std::max(largest, i - begin);
      begin = i;
    }
    const std::size_t min_size = std::max<std::size_t>(8, largest / 50);
    std::vector<std::pair<std::size_t, std::size_t>> rings, small;
    std::size_t in_rings = 0;
    for (const auto& c : clusters) {
      if (c.second - c.first < min_size) {
        small.push_back(c);
        continue;
      }
      rings.push_back(c);
      in_rings += c.second - c.first;
    }
    if (rings.size() < 2 || rings.size() > n / 16) continue;
    bool separated = true;
    for (std::size_t k = 0; k + 1 < rings.size() && separated; ++k) {
      const double width =
          std::max(el[rings[k].second - 1] - el[rings[k].first], el[rings[k + 1].second - 1] - el[rings[k + 1].first]);
      separated = el[rings[k + 1].first] - el[rings[k].second - 1] >= 0.5 * width;
    }
    if (!separated) continue;
    auto median = [&el](const std::pair<std::size_t, std::size_t>& c) { return el[(c.first + c.second) / 2]; };
    std::set<double> elevations;
    std::vector<double> spacings;
    for (std::size_t k = 0; k < rings.size(); ++k) {
      elevations.insert(median(rings[k]));
      if (k > 0) spacings.push_back(median(rings[k]) - median(rings[k - 1]));
    }
    // A small cluster far from every ring is a ring of its own (a scan line with few returns);
    // near one, it is that ring's stray returns.
    const double spacing = MedianAbove(spacings, 0.0);
    std::sort(small.begin(), small.end(),
              [](const auto& a, const auto& b) { return a.second - a.first > b.second - b.first; });
    for (const auto& c : small) {
      const double m = median(c);
      const auto above = elevations.lower_bound(m);
      const bool near_above = above != elevations.end() && *above - m < 0.75 * spacing;
      const bool near_below = above != elevations.begin() && m - *std::prev(above) < 0.75 * spacing;
      if (near_above || near_below) continue;
      elevations.insert(m);
      in_rings += c.second - c.first;
    }
    if (n - in_rings > n / 100) continue;
    return std::vector<double>(elevations.rbegin(), elevations.rend());
  }
  return {};
}

// The data's azimuth extent: where the largest empty sector ends, and how far the data reach
// from there (radians, <= 2 pi).
struct AzimuthExtent {
  double lo = -M_PI;
  double extent = kTwoPi;
};

AzimuthExtent FindAzimuthExtent(const std::vector<Direction>& dirs) {
  std::vector<double> az(dirs.size());
  for (std::size_t i = 0; i < dirs.size(); ++i) az[i] = dirs[i].az;
  std::sort(az.begin(), az.end());
  AzimuthExtent e;
  double gap = az.front() + kTwoPi - az.back();  // the sector across +-pi
  e.lo = az.front();
  for (std::size_t i = 1; i < az.size(); ++i) {
    if (az[i] - az[i - 1] > gap) gap = az[i] - az[i - 1], e.lo = az[i];
  }
  e.extent = kTwoPi - gap;
  return e;
}

// Columns over the data's azimuth range when it is under half a turn (an RGB-D frame, a partial
// TLS scan), else a full turn from -pi, whose first and last columns are neighbours.
void SetAzimuthRange(const AzimuthExtent& extent, OrganizeOptions& options) {
  if (extent.extent < M_PI) {
    options.azimuth_start_rad = extent.lo - 0.5 * options.azimuth_step_rad;
    options.azimuth_span_rad = extent.extent + options.azimuth_step_rad;
  } else {
    options.azimuth_start_rad = -M_PI;
    options.azimuth_span_rad = 0.0;
  }
}

double Cells(const OrganizeOptions& o, double el_min, double el_max) {
  const double span = o.azimuth_span_rad > 0.0 ? o.azimuth_span_rad : kTwoPi;
  const double cols = std::max(1.0, std::ceil(span / o.azimuth_step_rad - 1e-9));
  const double rows = o.row_elevations_rad.empty() ? std::floor((el_max - el_min) / o.elevation_step_rad + 1e-9) + 1.0
                                                   : double(o.row_elevations_rad.size());
  return rows * cols;
}

OrganizeOptions RingOptions(const std::vector<Direction>& dirs) {
  OrganizeOptions options;
  std::vector<double> el(dirs.size());
  for (std::size_t i = 0; i < dirs.size(); ++i) el[i] = dirs[i].el;
  std::vector<double> rings = FindRings(std::move(el));
  if (rings.empty()) return options;
  // Each point's ring, as OrganizeCloud assigns it (nearest ring elevation).
  std::vector<double> neg_bounds;
  for (std::size_t r = 0; r + 1 < rings.size(); ++r) neg_bounds.push_back(-0.5 * (rings[r] + rings[r + 1]));
  std::vector<std::pair<int, double>> keyed(dirs.size());
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    const int ring =
        static_cast<int>(std::upper_bound(neg_bounds.begin(), neg_bounds.end(), -dirs[i].el) - neg_bounds.begin());
    keyed[i] = {ring, dirs[i].az};
  }
  const double step = MedianAzimuthStep(keyed);
  if (!(step > 2e-6 && step < M_PI / 2)) return options;
  options.azimuth_step_rad = step;
  options.row_elevations_rad = std::move(rings);
  options.max_column_shift = kRingColumnShift;
  SetAzimuthRange(FindAzimuthExtent(dirs), options);
  return options;
}

// The ring grid with its column step refined by a few factors (for an irregular azimuth
// spacing), coarsest first, within the cell budget.
std::vector<OrganizeOptions> RingCandidates(const OrganizeOptions& rings, double max_cells) {
  std::vector<OrganizeOptions> out;
  if (rings.row_elevations_rad.empty()) return out;
  for (const double f : kRefinements) {
    OrganizeOptions o = rings;
    o.azimuth_step_rad = rings.azimuth_step_rad / f;
    if (o.azimuth_step_rad < 2e-6) break;
    if (o.azimuth_span_rad > 0.0) o.azimuth_span_rad += o.azimuth_step_rad - rings.azimuth_step_rad;
    o.azimuth_start_rad = rings.azimuth_span_rad > 0.0
                              ? rings.azimuth_start_rad + 0.5 * (rings.azimuth_step_rad - o.azimuth_step_rad)
                              : rings.azimuth_start_rad;
    if (Cells(o, 0.0, 0.0) > max_cells) break;
    out.push_back(std::move(o));
  }
  return out;
}

// Uniform grids to try, by increasing cell count: two shapes, isotropic at the mean spacing and
// anisotropic at the median azimuth step within elevation bands (with the elevation step that
// gives the same cell area), each axis refined by the factors; only grids within the cell budget.
// When even the coarsest is over budget, the finest coarser isotropic grid that fits.
std::vector<OrganizeOptions> UniformCandidates(const std::vector<Direction>& dirs, double spacing, double max_cells) {
  double el_min = M_PI, el_max = -M_PI;
  for (const Direction& d : dirs) el_min = std::min(el_min, d.el), el_max = std::max(el_max, d.el);
  std::vector<std::pair<int, double>> keyed(dirs.size());
  for (std::size_t i = 0; i < dirs.size(); ++i)
    keyed[i] = {static_cast<int>((dirs[i].el - el_min) / spacing), dirs[i].az};
  const double az_step = MedianAzimuthStep(keyed);
  std::vector<std::pair<double, double>> shapes = {{spacing, spacing}};  // (azimuth, elevation) steps
  if (az_step > 0.0 && az_step < 0.9 * spacing && spacing * spacing / az_step < 32 * az_step)
    shapes.emplace_back(az_step, spacing * spacing / az_step);
  const AzimuthExtent extent = FindAzimuthExtent(dirs);
  auto grid = [&](double az, double el) {
    OrganizeOptions o;
    o.azimuth_step_rad = std::clamp(az, 2e-6, 0.5 * M_PI);
    o.elevation_step_rad = std::clamp(el, 2e-6, 0.5 * M_PI);
    o.elevation_min_rad = el_min;
    o.elevation_max_rad = el_max;
    o.max_column_shift = kUniformColumnShift;
    SetAzimuthRange(extent, o);
    return std::make_pair(Cells(o, el_min, el_max), o);
  };

  std::vector<std::pair<double, OrganizeOptions>> fits;
  for (const auto& [a, e] : shapes)
    for (const double fa : kRefinements)
      for (const double fe : kRefinements)
        if (auto g = grid(a / fa, e / fe); g.first <= max_cells) fits.push_back(std::move(g));
  std::stable_sort(fits.begin(), fits.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<OrganizeOptions> out;
  for (auto& g : fits) out.push_back(std::move(g.second));
  if (out.empty()) {
    for (double f = 0.7; f > 1e-3 && out.empty(); f *= 0.7)
      if (auto g = grid(spacing / f, spacing / f); g.first <= max_cells) out.push_back(std::move(g.second));
  }
  return out;
}

// Usable points equal to another usable point (all but one of each group of equal points).
std::size_t CountRepeatedPoints(const std::vector<Eigen::Vector3f>& points) {
  std::vector<std::array<float, 3>> xyz;
  xyz.reserve(points.size());
  for (const auto& p : points)
    if (p.allFinite() && p.squaredNorm() != 0.0f) xyz.push_back({p.x(), p.y(), p.z()});
  std::sort(xyz.begin(), xyz.end());
  std::size_t repeated = 0;
  for (std::size_t i = 1; i < xyz.size(); ++i) repeated += xyz[i] == xyz[i - 1];
  return repeated;
}

Error Failed(const std::string& source, const Error& error) {
  return MakeError(error.code, source + ": cannot organize the unorganized cloud around the scanner origin (" +
                                   error.message + "); is the scanner at the origin of the file's frame?");
}

// 69792 -> "69,792".
std::string Thousands(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), ",");
  return s;
}

}  // namespace

double DensityAngularStep(const std::vector<Eigen::Vector3f>& points) { return DensityStep(Directions(points)); }

OrganizeOptions RingGridOptions(const std::vector<Eigen::Vector3f>& points) {
  const std::vector<Direction> dirs = Directions(points);
  return dirs.empty() ? OrganizeOptions() : RingOptions(dirs);
}

Expected<Scan> OrganizeCloudByDensity(const std::vector<Eigen::Vector3f>& points, const std::vector<float>& reflectance,
                                      std::string name, const std::string& source, const std::vector<Rgb>& colour,
                                      const std::vector<double>& time, const std::vector<Eigen::Vector3f>& sensor) {
  const std::vector<Direction> dirs = Directions(points);
  const double spacing = DensityStep(dirs);
  if (dirs.empty() || spacing <= 0.0) {
    return MakeError(ErrorCode::kParseError,
                     source +
                         ": the cloud has no finite point away from the origin, so it cannot be organized "
                         "into a scan grid");
  }
  const std::size_t usable = dirs.size();
  // A point repeated exactly (some files hold every point twice) can only be kept once.
  const std::size_t repeated = CountRepeatedPoints(points);
  const std::size_t distinct = usable - repeated;
  const double max_cells = std::max(16.0, kMaxCellsPerPoint * double(distinct));
  const auto target = static_cast<std::size_t>(std::ceil(kTargetKept * double(distinct)));

  // Candidate grids are compared by how many points they keep (cheap: the directions are sorted
  // once); the first that keeps `target` points is taken, else the one that keeps most.
  const CloudProjection projection(points);
  std::optional<OrganizeOptions> best;
  std::size_t best_kept = 0;
  auto try_grid = [&](const OrganizeOptions& options) -> Status {
    Expected<std::size_t> kept = projection.CountKept(options);
    if (!kept) return kept.error();
    if (!best || *kept > best_kept) best = options, best_kept = *kept;
    return Status::Ok();
  };
  // Rings: unless the data's own steps keep `target` points, all refinements are tried (a few),
  // and the coarsest that keeps nearly as many points as the best of them is taken, so that
  // repeated directions do not refine the columns for nothing.
  {
    const std::vector<OrganizeOptions> grids = RingCandidates(RingOptions(dirs), max_cells);
    std::vector<std::size_t> kept(grids.size());
    std::size_t most = 0;
    for (std::size_t k = 0; k < grids.size(); ++k) {
      Expected<std::size_t> n = projection.CountKept(grids[k]);
      if (!n) return Failed(source, n.error());
      kept[k] = *n;
      most = std::max(most, *n);
      if (k == 0 && *n >= target) break;  // the coarsest will do
    }
    const double enough = std::min(double(target), double(most) - kRingsNearlyAsGood * double(distinct));
    for (std::size_t k = 0; k < grids.size(); ++k) {
      if (double(kept[k]) < enough) continue;
      best = grids[k], best_kept = kept[k];
      break;
    }
  }
  if (double(best_kept) < kRingsKept * double(distinct)) {
    for (const OrganizeOptions& options : UniformCandidates(dirs, spacing, max_cells)) {
      if (Status s = try_grid(options); !s) return Failed(source, s.error());
      if (best_kept >= target) break;
    }
  }
  if (!best) {
    return MakeError(ErrorCode::kParseError, source + ": cannot organize the cloud into a scan grid within " +
                                                 std::to_string(int(kMaxCellsPerPoint)) + " cells per point");
  }
  Expected<Scan> scan = projection.Organize(reflectance, *best, std::move(name), colour, time, sensor);
  if (!scan) return Failed(source, scan.error());
  const bool is_rings = !best->row_elevations_rad.empty();
  Log(LogLevel::kDebug, "organizing '" + source + "': " + Thousands(best_kept) + " of " + Thousands(usable) +
                            " points kept in a " + std::to_string(scan->rows) + " x " + std::to_string(scan->cols) +
                            (is_rings ? " grid, one row per ring" : " uniform grid"));
  // Seen from one place, (nearly) every distinct point has a cell of its own; a cloud whose points
  // crowd each other's cells was seen from several places, and its origin is no viewpoint.
  // Where the file gives each point's sensor position, those say it.
  scan->single_viewpoint = double(best_kept) >= kRingsKept * double(distinct) && !SensorsSpread(sensor);
  if (best_kept < usable) {
    const std::size_t off_grid = usable - best_kept;
    const std::size_t conflicts = off_grid - std::min(off_grid, repeated);
    std::string message = "organizing '" + source + "': " + Thousands(off_grid) + " of " + Thousands(usable) +
                          " points have no cell of the scan grid (";
    if (conflicts > 0) message += Thousands(conflicts) + " share a cell with a nearer point";
    if (conflicts > 0 && repeated > 0) message += ", ";
    if (repeated > 0) message += Thousands(repeated) + " repeat another point exactly";
    message += "); they are kept as a list and exported with the others";
    if (!scan->single_viewpoint)
      message += std::string("; the cloud was not seen from one place: the registration's geometry uses the list too, ") +
                 (scan->HasSensor() ? "and its links are judged on free space along its points' own sensor positions"
                                    : "and no link is judged on free space seen from its origin (the file gives no "
                                      "sensor position per point)");
    if (scan->single_viewpoint) Log(LogLevel::kInfo, message);
    else LogWarning(message);
  }
  return scan;
}

}  // namespace scanreg::io
