// The city scene (issue 13 item 7): a grid of blocks with streets that close loops, for campaigns of
// 100+ stations where drift and loop closure matter. Layout (world frame, z up): blocks of
// city_block_m, streets 2 * street_half_width_m wide between them, street centre lines at
// x = k P (k = 0..blocks_x) and y = k P (k = 0..blocks_y), P = block + street width. A ring of blocks
// outside those lines puts façades on both sides of every street the stations use.
#include <algorithm>
#include <cmath>

#include "core/simulate/random.h"
#include "core/simulate/scene.h"
#include "core/simulate/scene_builder.h"

namespace scanreg {

double CityPitch(const SceneOptions& o) { return o.city_block_m + 2.0 * o.street_half_width_m; }

namespace {

using sim::Builder;
using sim::Rng;
using Vec3 = Eigen::Vector3d;

// Half extents of an axis-aligned box from its size along a horizontal axis `a`, across it, and up.
Vec3 Half(const Vec3& a, double along, double across, double up) {
  return std::abs(a.x()) > 0.5 ? Vec3(along, across, up) : Vec3(across, along, up);
}

// The box face (+x, -x, +y, -y) whose outward normal is `n`.
int FaceOf(const Vec3& n) {
  if (std::abs(n.x()) > 0.5) return n.x() > 0 ? 0 : 1;
  return n.y() > 0 ? 2 : 3;
}

// One side of a block: buildings from `corner` along `a` for `length` metres, façades facing `out`.
void BlockSide(Builder& b, const Vec3& corner, const Vec3& a, const Vec3& out, double length) {
  Scene& s = b.scene;
  Rng& rng = b.rng;
  double u = 0.0;
  while (u < length - 4.0) {
    const double width = std::min(rng.Uniform(10.0, 24.0), length - u);
    const double depth = rng.Uniform(10.0, 16.0), height = rng.Uniform(9.0, 24.0);
    const double setback = rng.Uniform(0.0, 1.5);
    const Vec3 front = corner + (u + 0.5 * width) * a - setback * out;  // middle of the façade, on the ground
    b.Building(front - 0.5 * depth * out + Vec3(0, 0, 0.5 * height), Half(a, 0.5 * width, 0.5 * depth, 0.5 * height),
               FaceOf(out), width, rng.Chance(0.8));
    if (rng.Chance(0.6)) {  // a shop sign over the ground floor: distinctive, and a depth edge
      const double sw = rng.Uniform(2.0, std::min(8.0, std::max(2.5, width - 1.0)));
      const double at = rng.Uniform(-0.5 * (width - sw), 0.5 * (width - sw));
      s.AddBox(front + at * a + 0.1 * out + Vec3(0, 0, 3.2), Half(a, 0.5 * sw, 0.1, 0.4), 0.0,
               s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.3, 0.8)))));
    }
    for (double d = rng.Uniform(0.5, 3.0); d < width - 1.5; d += rng.Uniform(1.5, 6.0)) {  // doors, shop windows
      const double dw = rng.Uniform(0.9, 3.5), dh = rng.Uniform(2.0, 2.7);
      if (d + dw > width - 0.5) break;
      const int tex = rng.Chance(0.5) ? s.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.05, 0.25))))
                                      : s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.2, 0.6))));
      s.AddBox(corner + (u + d + 0.5 * dw) * a - (setback - 0.04) * out + Vec3(0, 0, 0.5 * dh),
               Half(a, 0.5 * dw, 0.04, 0.5 * dh), 0.0, tex);
      d += dw;
    }
    u += width;
    if (rng.Chance(0.1)) u += rng.Uniform(3.0, 6.0);  // an alley into the courtyard
  }
}

// Street furniture along one street between two crossings: origin on the centre line, `a` along it.
void Furniture(Builder& b, const SceneOptions& o, const Vec3& origin, const Vec3& a, double length) {
  Scene& s = b.scene;
  Rng& rng = b.rng;
  const Vec3 left = Vec3::UnitZ().cross(a);
  const double road = o.street_half_width_m - 3.5, yaw = std::atan2(a.y(), a.x());
  auto at = [&](double u, double v) { return Eigen::Vector2d((origin + u * a + v * left).head<2>()); };
  for (int side : {-1, 1}) {
    for (double u = rng.Uniform(2, 10); u < length - 2; u += rng.Uniform(9, 16)) {  // lamp posts, trees
      const Eigen::Vector2d p = at(u, side * (road + rng.Uniform(0.5, 0.9)));
      if (rng.Chance(0.5)) {
        const int metal = s.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.35, 0.6))));
        s.AddCylinder(p, rng.Uniform(0.07, 0.12), 0.0, rng.Uniform(6.0, 8.0), metal);
      } else {
        const int bark = s.AddTexture(b.Noisy(static_cast<float>(rng.Uniform(0.25, 0.4)), 0.12f, 0.25));
        s.AddCylinder(p, rng.Uniform(0.15, 0.3), 0.0, rng.Uniform(3.0, 5.0), bark);
      }
    }
    for (double u = rng.Uniform(3, 8); u < length - 4; u += rng.Uniform(5.0, 9.0)) {  // parked cars
      if (!rng.Chance(0.65)) continue;
      const Eigen::Vector2d p = at(u, side * (road - 1.2));
      const double car_yaw = yaw + rng.Uniform(-0.04, 0.04);
      const int body = s.AddTexture(b.Noisy(static_cast<float>(rng.Uniform(0.1, 0.9)), 0.02f, 1.0));
      const int glass = s.AddTexture(SurfaceTexture::Uniform(0.08f));
      s.AddBox(Vec3(p.x(), p.y(), 0.78), Vec3(2.2, 0.9, 0.45), car_yaw, body);
      s.AddBox(Vec3(p.x(), p.y(), 1.5), Vec3(1.15, 0.8, 0.27), car_yaw, {glass, glass, glass, glass, body, body});
    }
    for (double u = rng.Uniform(3, 10); u < length - 3; u += rng.Uniform(6, 14)) {  // kiosks, columns, benches, bins
      const Eigen::Vector2d p = at(u, side * rng.Uniform(road + 1.8, o.street_half_width_m - 1.5));
      const double r = rng.Uniform();
      if (r < 0.25) {
        const int poster = s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.4, 0.7))));
        const int roof = s.AddTexture(SurfaceTexture::Uniform(0.3f));
        s.AddBox(Vec3(p.x(), p.y(), 1.35), Vec3(1.3, 1.0, 1.35), yaw + rng.Uniform(-0.3, 0.3),
                 {poster, poster, poster, poster, roof, roof});
      } else if (r < 0.45) {
        s.AddCylinder(p, 0.6, 0.0, 2.8, s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.4, 0.7)))));
      } else if (r < 0.75) {
        s.AddBox(Vec3(p.x(), p.y(), 0.23), Vec3(0.9, 0.22, 0.23), yaw, s.AddTexture(b.Noisy(0.45f, 0.08f, 0.3)));
      } else {
        s.AddCylinder(p, 0.3, 0.0, 1.0, s.AddTexture(SurfaceTexture::Uniform(0.5f)));
      }
    }
  }
}

}  // namespace

std::vector<StreetLeg> CityStreets(const SceneOptions& o) {
  const double p = CityPitch(o), x = o.city_blocks_x * p, y = o.city_blocks_y * p;
  // First the ring round the whole grid, a closed loop; then the inner streets, along x alternating
  // direction, then along y.
  std::vector<StreetLeg> legs = {{Vec3(0, 0, 0), Vec3(x, 0, 0)},
                                 {Vec3(x, 0, 0), Vec3(x, y, 0)},
                                 {Vec3(x, y, 0), Vec3(0, y, 0)},
                                 {Vec3(0, y, 0), Vec3(0, 0, 0)}};
  for (int k = 1; k < o.city_blocks_y; ++k) {
    const Vec3 a(0, k * p, 0), b(x, k * p, 0);
    legs.push_back(k % 2 == 1 ? StreetLeg{b, a} : StreetLeg{a, b});
  }
  for (int k = 1; k < o.city_blocks_x; ++k) {
    const Vec3 a(k * p, 0, 0), b(k * p, y, 0);
    legs.push_back(k % 2 == 1 ? StreetLeg{a, b} : StreetLeg{b, a});
  }
  return legs;
}

void AddCity(const SceneOptions& o, Scene& scene, Rng& rng) {
  Builder b{scene, rng, false};
  const double p = CityPitch(o), w = o.street_half_width_m, block = o.city_block_m;
  const Vec3 middle(0.5 * o.city_blocks_x * p, 0.5 * o.city_blocks_y * p, 0.0);
  const SurfaceTexture ground = sim::Pavement(b.Seed(), false);
  scene.AddRectangle(middle, Vec3::UnitX(), Vec3::UnitY(), middle.x() + p + 300.0, middle.y() + p + 300.0,
                     scene.AddTexture(ground));
  // Blocks -1..blocks (a ring outside the streets the stations use); block (i, j) spans
  // [i P + w, i P + w + block] x [j P + w, j P + w + block].
  for (int i = -1; i <= o.city_blocks_x; ++i)
    for (int j = -1; j <= o.city_blocks_y; ++j) {
      const double x0 = i * p + w, y0 = j * p + w, x1 = x0 + block, y1 = y0 + block;
      BlockSide(b, Vec3(x0, y0, 0), Vec3::UnitX(), -Vec3::UnitY(), block);  // south side, facing -y
      BlockSide(b, Vec3(x1, y0, 0), Vec3::UnitY(), Vec3::UnitX(), block);   // east
      BlockSide(b, Vec3(x1, y1, 0), -Vec3::UnitX(), Vec3::UnitY(), block);  // north
      BlockSide(b, Vec3(x0, y1, 0), -Vec3::UnitY(), -Vec3::UnitX(), block);  // west
    }
  // Furniture along every street between two crossings (the crossings stay clear).
  for (int k = 0; k <= o.city_blocks_x; ++k)
    for (int j = -1; j <= o.city_blocks_y; ++j) Furniture(b, o, Vec3(k * p, j * p + w, 0), Vec3::UnitY(), block);
  for (int k = 0; k <= o.city_blocks_y; ++k)
    for (int i = -1; i <= o.city_blocks_x; ++i) Furniture(b, o, Vec3(i * p + w, k * p, 0), Vec3::UnitX(), block);
}

}  // namespace scanreg
