#include "core/simulate/scanner.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "core/simulate/random.h"

namespace scanreg {
namespace {

Status Invalid(const std::string& what) { return MakeError(ErrorCode::kInvalidArgument, "scanner options: " + what); }

constexpr double kDeg = M_PI / 180.0;

// Hash streams of a cell.
enum Stream : std::uint64_t {
  kMixedChance = 1,
  kMixedWeight = 2,
  kRangeNoise = 3,
  kReflNoise = 4,
  kAzimuthNoise = 5,
  kElevationNoise = 6
};

}  // namespace

Status ScannerOptions::Validate() const {
  if (cols < 8 || cols > 100000) return Invalid("columns " + std::to_string(cols) + " must be in [8, 100000]");
  if (rows < 2 || rows > 50000) return Invalid("rows " + std::to_string(rows) + " must be in [2, 50000]");
  // 17 bytes per cell, held per station: 100 M cells (1.7 GB a scan) is beyond any real scanner's panorama.
  if (static_cast<long long>(cols) * rows > 100'000'000LL) {
    return Invalid("a " + std::to_string(cols) + " x " + std::to_string(rows) +
                   " panorama has more than 100 million cells (1.7 GB per scan); choose a smaller size");
  }
  if (!(elevation_min_deg >= -90.0 && elevation_max_deg <= 90.0))
    return Invalid("elevations must lie within [-90, 90] degrees");
  if (!(elevation_min_deg < elevation_max_deg))
    return Invalid("elevation min " + std::to_string(elevation_min_deg) + "° must be below max " +
                   std::to_string(elevation_max_deg) + "°");
  if (!(min_range_m >= 0.0 && min_range_m < max_range_m && max_range_m <= 10000.0))
    return Invalid("ranges must satisfy 0 <= min < max <= 10000 m (min " + std::to_string(min_range_m) + ", max " +
                   std::to_string(max_range_m) + ")");
  if (!(range_noise_m >= 0.0 && range_noise_m < 1.0))
    return Invalid("range noise " + std::to_string(range_noise_m) + " m must be in [0, 1) m");
  if (!(range_noise_per_m >= 0.0 && range_noise_per_m < 0.01))
    return Invalid("range noise growth " + std::to_string(range_noise_per_m) + " m/m must be in [0, 0.01)");
  if (!(angle_noise_deg >= 0.0 && angle_noise_deg <= 1.0))
    return Invalid("angle noise " + std::to_string(angle_noise_deg) + "° must be in [0, 1]°");
  if (!(reflectance_noise >= 0.0 && reflectance_noise <= 1.0))
    return Invalid("reflectance noise " + std::to_string(reflectance_noise) + " must be in [0, 1]");
  if (!(falloff_range_m > 0.0)) return Invalid("fall-off range must be positive");
  if (!(min_return_signal >= 0.0 && min_return_signal < 1.0)) return Invalid("min return signal must be in [0, 1)");
  if (!(mixed_pixel_probability >= 0.0 && mixed_pixel_probability <= 1.0))
    return Invalid("mixed-pixel probability must be in [0, 1]");
  if (!(mixed_pixel_min_jump_m > 0.0)) return Invalid("mixed-pixel minimum jump must be positive");
  return Status::Ok();
}

Expected<Scan> SimulateScan(const Scene& scene, const Eigen::Isometry3d& world_from_scanner,
                            const ScannerOptions& options, std::string name, ProgressSink& progress,
                            const CancelToken& cancel, std::vector<std::uint8_t>* moving_cells) {
  if (Status s = options.Validate(); !s) return s.error();
  const int rows = options.rows, cols = options.cols;
  Scan scan(std::move(name), rows, cols);
  scan.angles.azimuth.resize(cols);
  scan.angles.elevation.resize(rows);
  std::vector<double> cos_az(cols), sin_az(cols), cos_el(rows), sin_el(rows);
  for (int c = 0; c < cols; ++c) {
    const double az = -M_PI + (c + 0.5) * 2.0 * M_PI / cols;
    scan.angles.azimuth[c] = static_cast<float>(az);
    cos_az[c] = std::cos(az);
    sin_az[c] = std::sin(az);
  }
  const double el_step = (options.elevation_max_deg - options.elevation_min_deg) * kDeg / rows;
  for (int r = 0; r < rows; ++r) {
    const double el = options.elevation_max_deg * kDeg - (r + 0.5) * el_step;
    scan.angles.elevation[r] = static_cast<float>(el);
    cos_el[r] = std::cos(el);
    sin_el[r] = std::sin(el);
  }

  // Pass 1: exact first-hit range and returned signal of every cell (0 = no return).
  const std::size_t n = scan.size();
  std::vector<float> range(n, 0.0f), signal(n, 0.0f);
  std::vector<int> primitive(n, -1);
  const Eigen::Matrix3d rot = world_from_scanner.linear();
  // The beam's footprint spans about one cell: a standard deviation of half the azimuth step.
  const double footprint_per_m = M_PI / cols;
  const Eigen::Vector3d origin = world_from_scanner.translation();
  std::atomic<bool> cancelled{false};
  std::atomic<int> rows_done{0};
  const int report_every = std::max(1, rows / 8);
  const std::string stage = "simulating scan " + scan.name;
#pragma omp parallel for schedule(dynamic, 4)
  for (int r = 0; r < rows; ++r) {
    if (cancelled.load(std::memory_order_relaxed)) continue;
    if (cancel.IsCancelled()) {
      cancelled.store(true);
      continue;
    }
    for (int c = 0; c < cols; ++c) {
      const Eigen::Vector3d dir = rot * Eigen::Vector3d(cos_el[r] * cos_az[c], cos_el[r] * sin_az[c], sin_el[r]);
      const auto hit = scene.Intersect(origin, dir, options.max_range_m, footprint_per_m);
      if (!hit || hit->range < options.min_range_m) continue;
      const double cos_incidence = std::abs(hit->normal.dot(dir));
      const double s = hit->albedo * cos_incidence / (1.0 + hit->range / options.falloff_range_m);
      if (s < options.min_return_signal) continue;  // too weak: lost
      const std::size_t i = scan.Index(r, c);
      range[i] = static_cast<float>(hit->range);
      signal[i] = static_cast<float>(s);
      primitive[i] = hit->primitive;
    }
    const int done = rows_done.fetch_add(1) + 1;
    if (done % report_every == 0) progress.Report(0.9 * done / rows, stage);
  }
  if (cancelled.load()) return MakeError(ErrorCode::kCancelled, "simulation of scan " + scan.name + " cancelled");

  // Pass 2: mixed pixels, noise, points in the scanner frame.
  const double sigma = options.range_noise_m, refl_sigma = options.reflectance_noise;
  const std::uint64_t seed = options.seed;
  const double angle_sigma = options.angle_noise_deg * kDeg;
  if (moving_cells) {
    moving_cells->assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) (*moving_cells)[i] = range[i] > 0.0f && scene.IsMoving(primitive[i]);
  }
#pragma omp parallel for schedule(static)
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = scan.Index(r, c);
      if (range[i] <= 0.0f) continue;
      double rho = range[i], refl = signal[i];
      if (options.mixed_pixels) {
        // The beam footprint straddles the neighbour on another surface with the largest range jump
        // (or the sky). A continuous surface seen at grazing incidence is not an edge.
        const std::size_t nb[4] = {scan.Index(r, (c + 1) % cols), scan.Index(r, (c + cols - 1) % cols),
                                   scan.Index(std::max(r - 1, 0), c), scan.Index(std::min(r + 1, rows - 1), c)};
        double best_jump = options.mixed_pixel_min_jump_m;
        std::size_t edge = n;  // n: none; neighbour index otherwise
        bool sky = false;
        for (std::size_t j : nb) {
          if (j == i) continue;
          if (range[j] <= 0.0f) {
            sky = true;
            continue;
          }
          if (primitive[j] == primitive[i]) continue;
          const double jump = std::abs(range[j] - range[i]);
          if (jump > best_jump) {
            best_jump = jump;
            edge = j;
          }
        }
        const std::uint64_t h = sim::Hash(seed, i, kMixedChance);
        if ((edge < n || sky) && sim::ToUnit(h) < options.mixed_pixel_probability) {
          const double w = 0.05 + 0.9 * sim::ToUnit(sim::Hash(seed, i, kMixedWeight));
          if (edge < n) {
            rho += w * (range[edge] - rho);  // a floating point between the two surfaces
            refl += w * (signal[edge] - refl);
          } else {
            refl *= 1.0 - 0.5 * w;  // part of the beam went to the sky
          }
        }
      }
      rho += (sigma + options.range_noise_per_m * rho) * sim::GaussianFromHash(sim::Hash(seed, i, kRangeNoise));
      refl += refl_sigma * sim::GaussianFromHash(sim::Hash(seed, i, kReflNoise));
      Eigen::Vector3d los(cos_el[r] * cos_az[c], cos_el[r] * sin_az[c], sin_el[r]);
      if (angle_sigma > 0.0) {  // the encoders' error: the point lies off the cell's nominal direction
        const double az = std::atan2(los.y(), los.x()) + angle_sigma * sim::GaussianFromHash(sim::Hash(seed, i, kAzimuthNoise));
        const double el = std::asin(los.z()) + angle_sigma * sim::GaussianFromHash(sim::Hash(seed, i, kElevationNoise));
        los = Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      }
      if (!options.reflectance) refl = 0.5;
      scan.Set(r, c, (rho * los).cast<float>(), static_cast<float>(std::clamp(refl, 0.0, 1.0)));
    }
  }
  scan.world_from_scan = Eigen::Isometry3d::Identity();
  scan.reference_world_from_scan = world_from_scanner;
  progress.Report(1.0, stage);
  return scan;
}

}  // namespace scanreg
