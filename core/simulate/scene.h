// Synthetic scenes of analytic primitives for the TLS simulator: rectangles (ground, walls),
// oriented boxes (buildings, cars, kiosks), vertical cylinders (poles, trunks, bins), spheres
// (survey targets). Each surface
// carries an albedo texture of its surface coordinates. World frame: z up, metres; the street of
// MakeScene runs along x with its centre line on y = 0 and the ground at z = 0.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/common/expected.h"
#include "core/simulate/texture.h"

namespace scanreg {

class Scene {
 public:
  struct Hit {
    double range = 0.0;        // metres along the (unit) ray
    Eigen::Vector3d normal;    // unit, facing the ray origin
    double albedo = 0.0;       // [0, 1] from the surface texture
    int primitive = -1;        // index in the order of Add* calls
  };

  int AddTexture(const SurfaceTexture& texture);
  // Rectangle centred at `center`, spanned by unit orthogonal axes u and v, half sizes in metres.
  // Texture coordinates: (offset along u, offset along v) from the centre.
  int AddRectangle(const Eigen::Vector3d& center, const Eigen::Vector3d& u_axis, const Eigen::Vector3d& v_axis,
                   double half_u, double half_v, int texture);
  // Box with its bottom at center.z - half.z, rotated by yaw (radians) about z. Faces in the order
  // +x, -x, +y, -y, +z, -z (box frame). Side-face texture coordinates: (horizontal offset from the
  // face's left edge seen from outside, height above the box's bottom); top/bottom: (x, y) offsets.
  int AddBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents, double yaw_rad,
             const std::array<int, 6>& face_textures);
  int AddBox(const Eigen::Vector3d& center, const Eigen::Vector3d& half_extents, double yaw_rad, int texture);
  // Vertical cylinder with a top cap. Texture coordinates: (arc length, height above z_min).
  int AddCylinder(const Eigen::Vector2d& center_xy, double radius, double z_min, double z_max, int texture);

  // Sphere (survey targets). Texture coordinates: (arc length about z, height above the centre).
  int AddSphere(const Eigen::Vector3d& center, double radius, int texture);

  // Builds the bounding-volume hierarchy; call after the last Add* and before Intersect.
  void Build();

  // First surface hit by the ray origin + t * dir, 0 < t <= max_range; dir must be unit length.
  // footprint_per_m: the standard deviation of the beam's footprint per metre of range (its albedo
  // is averaged over it where a texture has sharp edges). Thread-safe once built.
  std::optional<Hit> Intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_range,
                               double footprint_per_m = 0.0) const;
  // The same by testing every primitive (reference for tests).
  std::optional<Hit> IntersectBruteForce(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                         double max_range) const;

  int num_primitives() const { return static_cast<int>(prims_.size()); }
  // Primitives from `first` on are moving objects (traffic.h): present in this scan only.
  void set_first_moving(int first) { first_moving_ = first; }
  bool IsMoving(int primitive) const { return primitive >= first_moving_; }
  const Eigen::AlignedBox3d& primitive_bounds(int i) const { return prims_[i].bounds; }

 private:
  enum class Kind : std::uint8_t { kRectangle, kBox, kCylinder, kSphere };
  struct Primitive {
    Kind kind;
    Eigen::Vector3d center;
    Eigen::Matrix3d axes;       // rectangle: columns u, v, n; box: rotation (box -> world)
    Eigen::Vector3d half;       // rectangle: (hu, hv, 0); box: half extents; cylinder: (r, z_min, z_max); sphere: (r, 0, 0)
    std::array<int, 6> texture;
    Eigen::AlignedBox3d bounds;
  };
  struct Node {
    Eigen::AlignedBox3d bounds;
    int left = -1, right = -1;  // children (inner node)
    int first = 0, count = 0;   // range in order_ (leaf when count > 0)
  };

  // Ray-primitive test; on a hit closer than *t_best updates it and the hit's face/coords.
  bool HitPrimitive(int index, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double* t_best, int* face,
                    Eigen::Vector2d* uv, Eigen::Vector3d* normal) const;
  std::optional<Hit> MakeHit(int index, double t, int face, const Eigen::Vector2d& uv, const Eigen::Vector3d& normal,
                             const Eigen::Vector3d& dir, double footprint_half_m = 0.0) const;
  int BuildNode(int first, int count);

  std::vector<SurfaceTexture> textures_;
  std::vector<Primitive> prims_;
  std::vector<Node> nodes_;
  std::vector<int> order_;
  int first_moving_ = 1 << 30;
};

struct SceneOptions {
  enum class Kind {
    kStreet,           // varied buildings, textures, poles, cars, kiosks, benches; some uniform surfaces
    kRepeatedWindows,  // identical buildings and window grids on both sides, plain ground; only the
                       // street furniture (posts, trees, cars) is distinctive
    kCity,             // a grid of blocks whose streets close loops (scene_city.cc); street length unused
    kOffice,           // an office floor (scene_office.cc): a corridor along x, street_length_m long, with
                       // same-size rooms behind regularly spaced doors, ceiling lights, painted walls;
                       // furniture differs from room to room
    kOfficeIdentical,  // the same floor with every room furnished alike and both ends alike: symmetric
                       // under a 180° turn and periodic by one room along the corridor
  };
  Kind kind = Kind::kStreet;
  std::uint64_t seed = 1;
  double street_length_m = 100.0;  // length of the built-up street along x, centred on x = 0
  double street_half_width_m = 9.0;  // distance from the centre line to the nearest façades
  int city_blocks_x = 1, city_blocks_y = 1;  // kCity: blocks between the streets the stations use
  double city_block_m = 48.0;                // kCity: side of a block
  bool far_site = false;  // also build a separate cluster of buildings around FarSiteCenter()
  // Survey sphere targets (white, on a thin tripod pole down to the ground): their centres.
  std::vector<Eigen::Vector3d> sphere_targets;
  double sphere_target_radius_m = 0.0725;  // 145 mm spheres, a common size
  // Checkerboard targets: a square board (the pattern with a light margin) centred at `center`,
  // facing `normal`, the pattern's edges horizontal and vertical (on a vertical board).
  struct CheckerTarget {
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX();
    double size_m = 0.2;  // side of the 2 x 2 pattern
  };
  std::vector<CheckerTarget> checker_targets;

  Status Validate() const;
};

// A street's centre line from `from` to `to` (on the ground).
struct StreetLeg {
  Eigen::Vector3d from, to;
};
// kCity: every street the stations may use, in the order a surveyor walks them: the ring round the
// grid (a closed loop), then the inner streets along x, then along y.
std::vector<StreetLeg> CityStreets(const SceneOptions& options);
// kCity: the distance between two crossings along a street.
double CityPitch(const SceneOptions& options);

// Centre (on the ground) of the far site: > 1 km from the street, beyond any scanner's range.
Eigen::Vector3d FarSiteCenter();

Scene MakeScene(const SceneOptions& options);

}  // namespace scanreg
