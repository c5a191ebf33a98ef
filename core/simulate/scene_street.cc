// MakeScene: the street and repeated-window scenes, and the far site. Layout (world frame, z up):
// the street runs along x over [-L/2, L/2]; road |y| < W - 3.5, sidewalks up to the façades at
// |y| >= W; a closing building at each end; the far site is a courtyard around FarSiteCenter().
#include <algorithm>
#include <cmath>
#include <string>

#include "core/simulate/random.h"
#include "core/simulate/scene.h"
#include "core/simulate/scene_builder.h"

namespace scanreg {
namespace {

using sim::Rng;
using sim::Builder;
using Vec3 = Eigen::Vector3d;

SurfaceTexture GroundTexture(const SceneOptions& o, Rng& rng, bool repeated) {
  SurfaceTexture t = sim::Pavement(rng.Next(), repeated);
  t.ground.enabled = true;
  t.ground.road_half_width = o.street_half_width_m - 3.5;
  t.ground.sidewalk_outer = o.street_half_width_m + 0.3;
  if (!repeated) {
    t.ground.crosswalk_u[0] = rng.Uniform(-0.3, -0.05) * o.street_length_m;
    t.ground.crosswalk_u[1] = rng.Uniform(0.1, 0.35) * o.street_length_m;
  }
  return t;
}

void StreetFurniture(const SceneOptions& o, Builder& b) {
  Scene& s = b.scene;
  Rng& rng = b.rng;
  const double half_l = 0.5 * o.street_length_m, road = o.street_half_width_m - 3.5;
  for (int side : {-1, 1}) {
    // Lamp posts and tree trunks along the kerb.
    for (double x = -half_l + rng.Uniform(2, 10); x < half_l; x += rng.Uniform(9, 16)) {
      const double y = side * (road + rng.Uniform(0.5, 0.9));
      if (rng.Chance(0.5)) {
        const int metal = s.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.35, 0.6))));
        const double h = rng.Uniform(6.0, 8.0);
        s.AddCylinder({x, y}, rng.Uniform(0.07, 0.12), 0.0, h, metal);
        s.AddBox(Vec3(x, y - side * 0.4, h - 0.1), Vec3(0.15, 0.4, 0.1), 0.0, metal);
      } else {
        const int bark = s.AddTexture(b.Noisy(static_cast<float>(rng.Uniform(0.25, 0.4)), 0.12f, 0.25));
        s.AddCylinder({x, y}, rng.Uniform(0.15, 0.3), 0.0, rng.Uniform(3.0, 5.0), bark);
      }
    }
    // Parked cars: body (clear of the ground) and cabin.
    for (double x = -half_l + rng.Uniform(0, 6); x < half_l - 4; x += rng.Uniform(5.0, 9.0)) {
      if (!rng.Chance(0.65)) continue;
      const double y = side * (road - 1.2), yaw = rng.Uniform(-0.04, 0.04);
      SurfaceTexture paint = b.Noisy(static_cast<float>(rng.Uniform(0.1, 0.9)), 0.02f, 1.0);
      const int body = s.AddTexture(paint);
      const int glass = s.AddTexture(SurfaceTexture::Uniform(0.08f));
      s.AddBox(Vec3(x, y, 0.78), Vec3(2.2, 0.9, 0.45), yaw, body);
      s.AddBox(Vec3(x - 0.2, y, 1.5), Vec3(1.15, 0.8, 0.27), yaw, {glass, glass, glass, glass, body, body});
    }
    // Sidewalk objects: kiosks and advertising columns (posters), benches, bins.
    for (double x = -half_l + rng.Uniform(3, 10); x < half_l - 3; x += rng.Uniform(6, 14)) {
      const double y = side * rng.Uniform(road + 1.8, o.street_half_width_m - 1.5);
      const double u = rng.Uniform();
      if (u < 0.25) {
        const int poster = s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.4, 0.7))));
        const int roof = s.AddTexture(SurfaceTexture::Uniform(0.3f));
        s.AddBox(Vec3(x, y, 1.35), Vec3(1.3, 1.0, 1.35), rng.Uniform(-0.3, 0.3),
                 {poster, poster, poster, poster, roof, roof});
      } else if (u < 0.45) {
        s.AddCylinder({x, y}, 0.6, 0.0, 2.8, s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.4, 0.7)))));
      } else if (u < 0.75) {
        const int wood = s.AddTexture(b.Noisy(0.45f, 0.08f, 0.3));
        s.AddBox(Vec3(x, y, 0.23), Vec3(0.9, 0.22, 0.23), 0.0, wood);
      } else {
        s.AddCylinder({x, y}, 0.3, 0.0, 1.0, s.AddTexture(SurfaceTexture::Uniform(0.5f)));
      }
    }
  }
}

void StreetBuildings(const SceneOptions& o, Builder& b) {
  Scene& s = b.scene;
  Rng& rng = b.rng;
  const double half_l = 0.5 * o.street_length_m, w = o.street_half_width_m;
  SurfaceTexture shared_facade;  // kRepeatedWindows: one façade for every building
  if (b.repeated) shared_facade = b.Facade(20.0, 15.0, false);
  for (int side : {-1, 1}) {
    double x = -half_l - 5.0;
    while (x < half_l + 5.0) {
      const double width = b.repeated ? 20.0 : std::min(rng.Uniform(10.0, 24.0), half_l + 5.0 - x);
      if (width < 4.0) break;
      const double depth = b.repeated ? 12.0 : rng.Uniform(10.0, 16.0);
      const double height = b.repeated ? 15.0 : rng.Uniform(9.0, 24.0);
      const double setback = b.repeated ? w : w + rng.Uniform(0.0, 1.5);
      const Vec3 center(x + 0.5 * width, side * (setback + 0.5 * depth), 0.5 * height);
      const Vec3 half(0.5 * width, 0.5 * depth, 0.5 * height);
      const int facade = side > 0 ? 3 : 2;  // the face looking at the street
      if (b.repeated) {
        const int front = s.AddTexture(shared_facade), plain = s.AddTexture(SurfaceTexture::Uniform(0.55f));
        std::array<int, 6> faces;
        faces.fill(plain);
        faces[facade] = front;
        s.AddBox(center, half, 0.0, faces);
        x += width;
        continue;
      }
      b.Building(center, half, facade, width, rng.Chance(0.8));
      // A shop sign (distinctive) or a ledge (plain) over the ground floor: a depth edge.
      const double fy = side * (setback - 0.1);
      if (rng.Chance(0.6)) {
        const double sw = rng.Uniform(2.0, std::min(8.0, width - 1.0));
        const int sign = s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.3, 0.8))));
        s.AddBox(Vec3(x + rng.Uniform(0.5, width - sw - 0.5) + 0.5 * sw, fy, 3.2), Vec3(0.5 * sw, 0.1, 0.4), 0.0,
                 sign);
      } else {
        s.AddBox(Vec3(center.x(), fy, 3.3), Vec3(0.5 * width, 0.12, 0.1), 0.0,
                 s.AddTexture(SurfaceTexture::Uniform(0.7f)));
      }
      // Doors and shop windows in the ground floor: irregular, non-periodic detail near the scanner.
      for (double u = rng.Uniform(0.5, 3.0); u < width - 1.5; u += rng.Uniform(1.5, 6.0)) {
        const double dw = rng.Uniform(0.9, 3.5), dh = rng.Uniform(2.0, 2.7);
        if (u + dw > width - 0.5) break;
        const int tex = rng.Chance(0.5)
                            ? s.AddTexture(SurfaceTexture::Uniform(static_cast<float>(rng.Uniform(0.05, 0.25))))
                            : s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.2, 0.6))));
        s.AddBox(Vec3(x + u + 0.5 * dw, side * (setback - 0.04), 0.5 * dh), Vec3(0.5 * dw, 0.04, 0.5 * dh), 0.0, tex);
        u += dw;
      }
      x += width;
      if (rng.Chance(0.3)) {  // an alley, sometimes closed by a plain garden wall
        const double gap = rng.Uniform(3.0, 8.0);
        if (rng.Chance(0.5)) {
          const int wall = s.AddTexture(rng.Chance(0.5) ? SurfaceTexture::Uniform(0.6f) : b.Noisy(0.5f, 0.1f, 1.5));
          s.AddBox(Vec3(x + 0.5 * gap, side * (w + 0.8), 1.1), Vec3(0.5 * gap, 0.15, 1.1), 0.0, wall);
        }
        x += gap;
      }
    }
  }
  // Buildings closing both ends of the street.
  for (int end : {-1, 1}) {
    const double height = b.repeated ? 15.0 : rng.Uniform(14.0, 20.0);
    const Vec3 center(end * (half_l + 25.0 + 6.0), 0.0, 0.5 * height);
    const Vec3 half(6.0, 40.0, 0.5 * height);
    const int facade = end > 0 ? 1 : 0;
    if (b.repeated) {
      SurfaceTexture wide = shared_facade;  // the same windows across the whole 80 m façade
      wide.windows.u_max = 80.0 - wide.windows.u_min;
      const int front = s.AddTexture(wide), plain = s.AddTexture(SurfaceTexture::Uniform(0.55f));
      std::array<int, 6> faces;
      faces.fill(plain);
      faces[facade] = front;
      s.AddBox(center, half, 0.0, faces);
    } else {
      b.Building(center, half, facade, 80.0, true);
    }
  }
}

void FarSite(Builder& b) {
  Scene& s = b.scene;
  Rng& rng = b.rng;
  const Vec3 c = FarSiteCenter();
  SurfaceTexture gravel = b.Noisy(0.35f, 0.08f, 2.0);
  gravel.blob_contrast = 0.1f;
  gravel.blob_probability = 0.4;
  s.AddRectangle(c, Vec3::UnitX(), Vec3::UnitY(), 250.0, 250.0, s.AddTexture(gravel));
  // A courtyard: four buildings facing its centre (face index of the inner façade).
  const Vec3 offsets[4] = {{25, 0, 0}, {-25, 0, 0}, {0, 25, 0}, {0, -25, 0}};
  const int facades[4] = {1, 0, 3, 2};
  for (int i = 0; i < 4; ++i) {
    const double height = rng.Uniform(10.0, 20.0);
    const bool along_y = i < 2;
    const Vec3 half = along_y ? Vec3(6.0, 20.0, 0.5 * height) : Vec3(16.0, 6.0, 0.5 * height);
    const Vec3 center = c + offsets[i] + Vec3(0, 0, 0.5 * height) + (offsets[i].normalized() * 6.0);
    b.Building(center, half, facades[i], along_y ? 40.0 : 32.0, true);
  }
  const int bark = s.AddTexture(b.Noisy(0.3f, 0.12f, 0.25));
  for (int i = 0; i < 6; ++i)
    s.AddCylinder({c.x() + rng.Uniform(-12, 12), c.y() + rng.Uniform(-12, 12)}, 0.25, 0.0, 4.0, bark);
}

}  // namespace

Eigen::Vector3d FarSiteCenter() { return Eigen::Vector3d(1500.0, 900.0, 0.0); }

Status SceneOptions::Validate() const {
  if (!(street_length_m >= 20.0 && street_length_m <= 1000.0))
    return MakeError(ErrorCode::kInvalidArgument,
                     "scene street length " + std::to_string(street_length_m) + " m is outside [20, 1000] m");
  if (!(street_half_width_m >= 6.0 && street_half_width_m <= 50.0))
    return MakeError(ErrorCode::kInvalidArgument, "scene street half-width " + std::to_string(street_half_width_m) +
                                                      " m is outside [6, 50] m");
  if (kind == Kind::kCity && !(city_blocks_x >= 1 && city_blocks_y >= 1 && city_blocks_x * city_blocks_y <= 100))
    return MakeError(ErrorCode::kInvalidArgument, "scene: a city of " + std::to_string(city_blocks_x) + " x " +
                                                      std::to_string(city_blocks_y) + " blocks; use 1 to 100 blocks");
  if (kind == Kind::kCity && !(city_block_m >= 20.0 && city_block_m <= 200.0))
    return MakeError(ErrorCode::kInvalidArgument,
                     "scene: city block " + std::to_string(city_block_m) + " m is outside [20, 200] m");
  if (!sphere_targets.empty() && !(sphere_target_radius_m >= 0.01 && sphere_target_radius_m <= 1.0))
    return MakeError(ErrorCode::kInvalidArgument, "scene: sphere target radius " +
                                                      std::to_string(sphere_target_radius_m) + " m is outside [0.01, 1] m");
  for (const Vec3& c : sphere_targets)
    if (!c.allFinite()) return MakeError(ErrorCode::kInvalidArgument, "scene: a sphere target centre is not finite");
  for (const CheckerTarget& t : checker_targets) {
    if (!t.center.allFinite() || !t.normal.allFinite() || t.normal.norm() < 1e-6)
      return MakeError(ErrorCode::kInvalidArgument, "scene: a checkerboard target's centre or normal is not valid");
    if (!(t.size_m >= 0.02 && t.size_m <= 2.0))
      return MakeError(ErrorCode::kInvalidArgument, "scene: checkerboard size " + std::to_string(t.size_m) +
                                                        " m is outside [0.02, 2] m");
  }
  return Status::Ok();
}

Scene MakeScene(const SceneOptions& options) {
  SceneOptions o = options;  // out-of-range values are clamped (Validate reports them)
  o.street_length_m = std::clamp(o.street_length_m, 20.0, 1000.0);
  o.street_half_width_m = std::clamp(o.street_half_width_m, 6.0, 50.0);
  const bool repeated = o.kind == SceneOptions::Kind::kRepeatedWindows;
  Scene scene;
  Rng rng(sim::Hash(o.seed, static_cast<int>(o.kind) + 1));
  Builder b{scene, rng, repeated};
  if (o.kind == SceneOptions::Kind::kCity) {
    AddCity(o, scene, rng);
  } else if (IsOffice(o.kind)) {
    AddOffice(o, scene, rng);
  } else {
    // The ground: large enough that a scanner anywhere on the street sees ground to its max range.
    scene.AddRectangle(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), 0.5 * o.street_length_m + 300.0, 300.0,
                       scene.AddTexture(GroundTexture(o, rng, repeated)));
    StreetBuildings(o, b);
    StreetFurniture(o, b);  // real streets always hold some unique objects, even between identical façades
  }
  if (o.far_site) FarSite(b);
  if (!o.sphere_targets.empty()) {
    const int white = scene.AddTexture(SurfaceTexture::Uniform(0.85f)), pole = scene.AddTexture(SurfaceTexture::Uniform(0.3f));
    const double r = o.sphere_target_radius_m;
    for (const Vec3& c : o.sphere_targets) {
      scene.AddSphere(c, r, white);
      if (c.z() - r > 0.05) scene.AddCylinder({c.x(), c.y()}, std::min(0.012, 0.3 * r), 0.0, c.z() - 0.9 * r, pole);
    }
  }
  for (const SceneOptions::CheckerTarget& t : o.checker_targets) {
    const Vec3 n = t.normal.normalized();
    Vec3 u = Vec3::UnitZ().cross(n);  // horizontal on a vertical board
    u = u.norm() > 1e-6 ? u.normalized() : Vec3::UnitX();
    SurfaceTexture checker = SurfaceTexture::Uniform(0.9f);  // the light margin round the pattern
    checker.checker_half_m = 0.5 * t.size_m;
    scene.AddRectangle(t.center, u, n.cross(u), 0.625 * t.size_m, 0.625 * t.size_m, scene.AddTexture(checker));
  }
  scene.Build();
  return scene;
}

}  // namespace scanreg
