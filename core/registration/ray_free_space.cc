#include "core/registration/ray_free_space.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <omp.h>

namespace scanreg {
namespace {

constexpr std::int64_t kHalf = std::int64_t(1) << 20;  // 21 bits an axis: +-2^20 cubes from the origin

bool Packable(std::int64_t x, std::int64_t y, std::int64_t z) {
  return x >= -kHalf && x < kHalf && y >= -kHalf && y < kHalf && z >= -kHalf && z < kHalf;
}

std::uint64_t Pack(std::int64_t x, std::int64_t y, std::int64_t z) {
  return (std::uint64_t(x + kHalf) << 42) | (std::uint64_t(y + kHalf) << 21) | std::uint64_t(z + kHalf);
}

// The cube of a point in cube units; false beyond the packable range (or not finite).
bool CubeOf(const Eigen::Vector3d& x, std::int64_t c[3]) {
  for (int k = 0; k < 3; ++k) {
    const double f = std::floor(x[k]);
    if (!(f >= -double(kHalf) && f < double(kHalf))) return false;
    c[k] = static_cast<std::int64_t>(f);
  }
  return true;
}

void SortUnique(std::vector<std::uint64_t>* keys) {
  std::sort(keys->begin(), keys->end());
  keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
  keys->shrink_to_fit();
}

// Appends the cubes the segment a -> b (in cube units) passes through (Amanatides & Woo's walk), as
// far as they are packable; false when a starts outside.
bool Walk(const Eigen::Vector3d& a, const Eigen::Vector3d& b, std::vector<std::uint64_t>* out) {
  std::int64_t cube[3];
  if (!CubeOf(a, cube)) return false;
  int step[3];
  double t_max[3], t_delta[3];
  const Eigen::Vector3d d = b - a;
  for (int k = 0; k < 3; ++k) {
    step[k] = d[k] > 0 ? 1 : -1;
    if (d[k] == 0.0) {
      t_max[k] = t_delta[k] = std::numeric_limits<double>::infinity();
    } else {
      const double boundary = double(cube[k]) + (d[k] > 0 ? 1.0 : 0.0);
      t_max[k] = (boundary - a[k]) / d[k];
      t_delta[k] = std::abs(1.0 / d[k]);
    }
  }
  for (;;) {
    if (!Packable(cube[0], cube[1], cube[2])) return true;
    out->push_back(Pack(cube[0], cube[1], cube[2]));
    const int k = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if (!(t_max[k] <= 1.0)) return true;
    cube[k] += step[k];
    t_max[k] += t_delta[k];
  }
}

}  // namespace

RayFreeSpace::RayFreeSpace(const Scan& scan, double cell_m, std::size_t max_cells) : cell_(cell_m) {
  if (!scan.HasSensor() || !(cell_m > 0.0)) return;
  // Every return with its sensor position, the grid's first: ray k is valid cell cells[k], or listed
  // point k - cells.size().
  std::vector<std::uint32_t> cells;
  cells.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) cells.push_back(static_cast<std::uint32_t>(i));
  const std::size_t n = cells.size() + scan.list_points.size();
  if (n == 0) return;
  auto ray = [&](std::size_t k) -> std::pair<const Eigen::Vector3f&, const Eigen::Vector3f&> {
    if (k < cells.size()) return {scan.sensor[cells[k]], scan.points[cells[k]]};
    return {scan.list_sensor[k - cells.size()], scan.list_points[k - cells.size()]};
  };
  const double inv = 1.0 / cell_m;
  // Surface: the cube of every return.
  surface_.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    std::int64_t c[3];
    if (CubeOf(ray(k).second.cast<double>() * inv, c)) surface_.push_back(Pack(c[0], c[1], c[2]));
  }
  SortUnique(&surface_);
  // Free: the rays, evenly over the returns, as many as max_cells cubes allow.
  double length = 0.0;  // mean ray length in cubes, from a sample
  const std::size_t probe = std::min<std::size_t>(n, 1000);
  for (std::size_t k = 0; k < probe; ++k) {
    const auto [s, p] = ray(k * n / probe);
    length += (p - s).norm() * inv;
  }
  length = std::isfinite(length) ? std::max(1.0, length / double(probe)) : 1.0;
  const std::size_t wanted = std::min(n, std::max<std::size_t>(1, std::size_t(double(max_cells) / (length + 1.0))));
  const double stride = double(n) / double(wanted);
  std::vector<std::vector<std::uint64_t>> parts(static_cast<std::size_t>(omp_get_max_threads()));
  int traced = 0;
#pragma omp parallel reduction(+ : traced)
  {
    std::vector<std::uint64_t>& out = parts[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (long k = 0; k < static_cast<long>(wanted); ++k) {
      const auto [s, p] = ray(static_cast<std::size_t>(double(k) * stride));
      const Eigen::Vector3d a = s.cast<double>() * inv, b = p.cast<double>() * inv;
      const double cubes = (b - a).norm();
      if (!(cubes > 3.0) || !std::isfinite(cubes)) continue;  // no room before the margin
      if (Walk(a, a + (b - a) * ((cubes - 2.0) / cubes), &out)) ++traced;
    }
  }
  rays_ = traced;
  std::size_t total = 0;
  for (const auto& part : parts) total += part.size();
  free_.reserve(total);
  for (auto& part : parts) {
    free_.insert(free_.end(), part.begin(), part.end());
    std::vector<std::uint64_t>().swap(part);
  }
  SortUnique(&free_);
}

bool RayFreeSpace::Has(const std::vector<std::uint64_t>& set, std::int64_t x, std::int64_t y, std::int64_t z) const {
  return Packable(x, y, z) && std::binary_search(set.begin(), set.end(), Pack(x, y, z));
}

bool RayFreeSpace::NearSurface(std::int64_t x, std::int64_t y, std::int64_t z) const {
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (Has(surface_, x + dx, y + dy, z + dz)) return true;
  return false;
}

RayFreeSpace::Seen RayFreeSpace::At(const Eigen::Vector3d& p) const {
  std::int64_t c[3];
  if (!known() || !CubeOf(p / cell_, c)) return Seen::kUnseen;
  if (NearSurface(c[0], c[1], c[2])) return Seen::kSurface;
  return Has(free_, c[0], c[1], c[2]) ? Seen::kFree : Seen::kUnseen;
}

bool RayFreeSpace::Free(const Eigen::Vector3d& p) const {
  std::int64_t c[3];
  if (!known() || !CubeOf(p / cell_, c)) return false;
  return Has(free_, c[0], c[1], c[2]) && !NearSurface(c[0], c[1], c[2]);  // most cubes are not free: one lookup
}

}  // namespace scanreg
