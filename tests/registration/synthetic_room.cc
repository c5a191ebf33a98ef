#include "tests/registration/synthetic_room.h"

#include <cmath>
#include <limits>
#include <random>

namespace scanreg::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Slab test: entry and exit distances of the ray o + t d through the box.
void Slabs(const AxisBox& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t_in, double* t_out) {
  double lo = -kInf, hi = kInf;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d(k)) < 1e-15) {
      if (o(k) < b.min(k) || o(k) > b.max(k)) {
        lo = kInf;
        hi = -kInf;
      }
      continue;
    }
    double t0 = (b.min(k) - o(k)) / d(k), t1 = (b.max(k) - o(k)) / d(k);
    if (t0 > t1) std::swap(t0, t1);
    lo = std::max(lo, t0);
    hi = std::min(hi, t1);
  }
  *t_in = lo;
  *t_out = hi;
}

}  // namespace

AxisBox DefaultRoom() { return {{-6.0, -4.0, 0.0}, {6.0, 4.0, 3.0}}; }

std::vector<AxisBox> DefaultBlocks() {
  return {{{2.0, 1.0, 0.0}, {3.0, 2.0, 1.0}},
          {{-4.0, -3.0, 0.0}, {-3.0, -1.5, 2.0}},
          {{1.0, -3.5, 0.0}, {1.5, -2.0, 2.5}},
          {{-2.0, 2.0, 1.0}, {-1.0, 3.0, 1.5}}};
}

Scan CastRoomScan(const Eigen::Isometry3d& world_from_scan, int rows, int cols, const AxisBox& room,
                  const std::vector<AxisBox>& blocks, double range_sigma_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, range_sigma_m > 0.0 ? range_sigma_m : 1.0);
  Scan scan("room", rows, cols);
  scan.world_from_scan = world_from_scan;
  const double el_max = 60.0 * kPi / 180.0;
  for (int c = 0; c < cols; ++c) scan.angles.azimuth.push_back(static_cast<float>(-kPi + (c + 0.5) * 2.0 * kPi / cols));
  for (int r = 0; r < rows; ++r)
    scan.angles.elevation.push_back(static_cast<float>(el_max - 2.0 * el_max * r / std::max(rows - 1, 1)));
  const Eigen::Vector3d o = world_from_scan.translation();
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const double az = scan.angles.azimuth[c], el = scan.angles.elevation[r];
      const Eigen::Vector3d d_scan(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const Eigen::Vector3d d = world_from_scan.linear() * d_scan;
      double t_in, t_out;
      Slabs(room, o, d, &t_in, &t_out);
      double t = t_out;  // inside the room: the ray leaves through a wall
      for (const AxisBox& b : blocks) {
        Slabs(b, o, d, &t_in, &t_out);
        if (t_in <= t_out && t_in > 1e-6 && t_in < t) t = t_in;
      }
      if (!std::isfinite(t) || t <= 0.0) continue;
      if (range_sigma_m > 0.0) t += noise(rng);
      scan.Set(r, c, (d_scan * t).cast<float>(), 0.5f);
    }
  }
  return scan;
}

Eigen::Isometry3d RoomStation(double x, double y, double heading_deg) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(x, y, 1.5));
  t.rotate(Eigen::AngleAxisd(heading_deg * kPi / 180, Eigen::Vector3d::UnitZ()));
  return t;
}

Eigen::Isometry3d MovedPose(const Eigen::Isometry3d& pose, double mm, double deg, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
  d.linear() = Eigen::AngleAxisd(deg * kPi / 180, Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
  d.translation() = 1e-3 * mm * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  return pose * d;
}

}  // namespace scanreg::testing
