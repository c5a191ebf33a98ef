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

void SortUnique(std::vector<std::uint64_t>* keys) {
  std::sort(keys->begin(), keys->end());
  keys->erase(std::unique(keys->begin(), keys->end()), keys->end());
  keys->shrink_to_fit();
}

// Appends the cubes the segment a -> b (in cube units) passes through (Amanatides & Woo's walk).
void Walk(const Eigen::Vector3d& a, const Eigen::Vector3d& b, std::vector<std::uint64_t>* out) {
  std::int64_t cube[3];
  int step[3];
  double t_max[3], t_delta[3];
  const Eigen::Vector3d d = b - a;
  for (int k = 0; k < 3; ++k) {
    cube[k] = static_cast<std::int64_t>(std::floor(a[k]));
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
    if (!Packable(cube[0], cube[1], cube[2])) return;
    out->push_back(Pack(cube[0], cube[1], cube[2]));
    const int k = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if (t_max[k] > 1.0) return;
    cube[k] += step[k];
    t_max[k] += t_delta[k];
  }
}

}  // namespace

RayFreeSpace::RayFreeSpace(const Scan& scan, double cell_m, std::size_t max_cells) : cell_(cell_m) {
  if (!scan.HasSensor() || !(cell_m > 0.0)) return;
  // Every return with its sensor position, the grid's first.
  std::vector<std::pair<Eigen::Vector3f, Eigen::Vector3f>> rays;  // (sensor, point)
  rays.reserve(scan.CountPoints());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) rays.emplace_back(scan.sensor[i], scan.points[i]);
  for (std::size_t i = 0; i < scan.list_points.size(); ++i) rays.emplace_back(scan.list_sensor[i], scan.list_points[i]);
  if (rays.empty()) return;
  const double inv = 1.0 / cell_m;
  auto cube_of = [inv](const Eigen::Vector3f& p) {
    return Eigen::Vector3d((p.cast<double>() * inv).array().floor());
  };
  // Surface: the cube of every return.
  surface_.reserve(rays.size());
  for (const auto& [s, p] : rays) {
    const Eigen::Vector3d c = cube_of(p);
    const auto x = static_cast<std::int64_t>(c.x()), y = static_cast<std::int64_t>(c.y()), z = static_cast<std::int64_t>(c.z());
    if (Packable(x, y, z)) surface_.push_back(Pack(x, y, z));
  }
  SortUnique(&surface_);
  // Free: the rays, evenly over the returns, as many as max_cells cubes allow.
  double length = 0.0;  // mean ray length in cubes, from a sample
  const std::size_t probe = std::min<std::size_t>(rays.size(), 1000);
  for (std::size_t k = 0; k < probe; ++k) {
    const auto& [s, p] = rays[k * rays.size() / probe];
    length += (p - s).norm() * inv;
  }
  length = std::max(1.0, length / double(probe));
  const std::size_t wanted = std::min(rays.size(), std::max<std::size_t>(1, std::size_t(double(max_cells) / (length + 1.0))));
  const double stride = double(rays.size()) / double(wanted);
  std::vector<std::vector<std::uint64_t>> parts(static_cast<std::size_t>(omp_get_max_threads()));
  int traced = 0;
#pragma omp parallel reduction(+ : traced)
  {
    std::vector<std::uint64_t>& out = parts[static_cast<std::size_t>(omp_get_thread_num())];
#pragma omp for schedule(static)
    for (long k = 0; k < static_cast<long>(wanted); ++k) {
      const auto& [s, p] = rays[static_cast<std::size_t>(double(k) * stride)];
      const Eigen::Vector3d a = s.cast<double>() * inv, b = p.cast<double>() * inv;
      const double cubes = (b - a).norm();
      if (!(cubes > 3.0) || !std::isfinite(cubes)) continue;  // no room before the margin
      Walk(a, a + (b - a) * ((cubes - 2.0) / cubes), &out);
      ++traced;
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

RayFreeSpace::Seen RayFreeSpace::At(const Eigen::Vector3d& p) const {
  if (!known() || !p.allFinite()) return Seen::kUnseen;
  const Eigen::Vector3d c = (p / cell_).array().floor();
  if (!(c.cwiseAbs().maxCoeff() < double(kHalf))) return Seen::kUnseen;
  const auto x = static_cast<std::int64_t>(c.x()), y = static_cast<std::int64_t>(c.y()), z = static_cast<std::int64_t>(c.z());
  for (int dx = -1; dx <= 1; ++dx)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dz = -1; dz <= 1; ++dz)
        if (Has(surface_, x + dx, y + dy, z + dz)) return Seen::kSurface;
  return Has(free_, x, y, z) ? Seen::kFree : Seen::kUnseen;
}

}  // namespace scanreg
