#include "core/simulate/traffic.h"

#include <algorithm>
#include <cmath>

#include "core/simulate/random.h"

namespace scanreg {
namespace {

using Vec3 = Eigen::Vector3d;

// True when the footprint (centre, half length along x, half width along y) keeps `clear` metres
// from the scanner's position.
bool ClearOf(const Vec3& station, double x, double y, double half_l, double half_w, double clear) {
  return std::abs(station.x() - x) > half_l + clear || std::abs(station.y() - y) > half_w + clear;
}

void AddVehicle(Scene& s, sim::Rng& rng, double x, double y, double half_l, double half_w, double height) {
  const double yaw = rng.Uniform(-0.05, 0.05);
  const int body = s.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.1, 0.9))));
  const int glass = s.AddTexture(SurfaceTexture::Uniform(0.08f));
  const double clearance = 0.3, lower = 0.55 * (height - clearance);
  s.AddBox(Vec3(x, y, clearance + 0.5 * lower), Vec3(half_l, half_w, 0.5 * lower), yaw, body);
  const double cabin_l = half_l > 3.0 ? half_l : 0.6 * half_l;  // buses and vans: cabin the full length
  const double upper = height - clearance - lower;
  s.AddBox(Vec3(x - (half_l - cabin_l) * 0.3, y, clearance + lower + 0.5 * upper), Vec3(cabin_l, 0.95 * half_w, 0.5 * upper),
           yaw, {glass, glass, glass, glass, body, body});
}

}  // namespace

int AddTraffic(Scene& scene, const SceneOptions& street, const Eigen::Vector3d& station, const TrafficOptions& options,
               std::uint64_t seed) {
  const int first = scene.num_primitives();
  sim::Rng rng(sim::Hash(seed, 0x7aff1c));
  const double road = street.street_half_width_m - 3.5;
  const double half_street = 0.5 * street.street_length_m;
  auto along = [&] {
    return std::clamp(station.x() + rng.Uniform(-options.reach_m, options.reach_m), -half_street + 6.0,
                      half_street - 6.0);
  };
  for (int i = 0; i < options.vehicles; ++i) {
    const double u = rng.Uniform();
    const double half_l = u < 1.0 / 16 ? 6.0 : u < 3.0 / 16 ? 2.8 : rng.Uniform(2.0, 2.4);
    const double half_w = u < 3.0 / 16 ? 1.25 : 0.9;
    const double height = u < 1.0 / 16 ? 3.2 : u < 3.0 / 16 ? 2.5 : rng.Uniform(1.4, 1.6);
    const double lane = (rng.Chance(0.5) ? 1.0 : -1.0) * 0.45 * road;
    for (int attempt = 0; attempt < 20; ++attempt) {
      const double x = along(), y = lane + rng.Uniform(-0.3, 0.3);
      if (!ClearOf(station, x, y, half_l, half_w, 1.5)) continue;
      AddVehicle(scene, rng, x, y, half_l, half_w, height);
      break;
    }
  }
  for (int i = 0; i < options.pedestrians; ++i) {
    const int skin = scene.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.15, 0.7))));
    for (int attempt = 0; attempt < 20; ++attempt) {
      const double x = along();
      const double side = rng.Chance(0.5) ? 1.0 : -1.0;
      const double y = rng.Chance(0.25) ? rng.Uniform(-road, road)  // crossing
                                        : side * rng.Uniform(road + 1.0, street.street_half_width_m - 0.6);
      if (!ClearOf(station, x, y, 0.3, 0.3, 1.5)) continue;
      const double height = rng.Uniform(1.5, 1.95);
      scene.AddCylinder({x, y}, rng.Uniform(0.18, 0.26), 0.0, height, skin);
      break;
    }
  }
  return first;
}

}  // namespace scanreg
