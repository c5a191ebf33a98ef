// The office-floor scene (issue 38): interiors where registration aliases. Layout (world frame, z up,
// metres): a corridor along x over [-L/2, L/2] (L = street_length_m rounded to whole rooms),
// |y| < kHalfCorridor, floor z = 0, ceiling z = kCeiling; same-size rooms on both sides behind walls
// of kWall, each with a door in the corridor wall at the same place in every room, a window in its
// outer wall and two ceiling lights; ceiling lights every kLightPitch along the corridor; painted
// walls of almost uniform albedo. kOffice: furniture and notice boards differ from room to room and
// the corridor's two ends differ. kOfficeIdentical: every room is furnished alike, the doors are
// centred, the ends are alike and the whole floor is symmetric under a 180° turn about its centre and
// periodic by one room along the corridor: only the ends tell the stations apart.
#include <algorithm>
#include <array>
#include <cmath>

#include "core/simulate/random.h"
#include "core/simulate/scene.h"
#include "core/simulate/scene_builder.h"

namespace scanreg {
namespace {

using sim::Builder;
using sim::Rng;
using Vec3 = Eigen::Vector3d;

constexpr double kHalfCorridor = 1.0;  // the corridor is 2 m wide
constexpr double kCeiling = 2.7;
constexpr double kWall = 0.12;
constexpr double kDoorWidth = 0.9, kDoorHeight = 2.1;
constexpr double kLightPitch = 3.0;

// An axis-aligned box spanning [lo, hi].
void Span(Scene& s, const Vec3& lo, const Vec3& hi, int texture) {
  const Vec3 half = 0.5 * (hi - lo);
  s.AddBox(lo + half, half, 0.0, texture);
}

// One piece of furniture in room coordinates: `a` along the corridor from the room's centre line,
// `b` into the room from the corridor wall's room face; sizes along a, b and up.
struct Piece {
  double a, b, size_a, size_b, height;
  bool round;  // a bin or a column: a cylinder of diameter size_a
};

// A room's furniture: desks with chairs, cabinets against the walls, a bin.
std::vector<Piece> Furniture(Rng& rng, double room_width, double depth) {
  std::vector<Piece> out;
  const int desks = 1 + static_cast<int>(rng.Uniform(0.0, 2.0));
  for (int d = 0; d < desks; ++d) {
    const double a = rng.Uniform(-0.5 * room_width + 1.0, 0.5 * room_width - 1.0);
    const double b = rng.Uniform(3.0, depth - 0.6);  // clear of the door and a station inside it
    out.push_back({a, b, 1.6, 0.8, 0.75, false});
    out.push_back({a + rng.Uniform(-0.4, 0.4), b - 0.75, 0.5, 0.5, rng.Uniform(0.85, 1.05), false});
  }
  const int cabinets = static_cast<int>(rng.Uniform(0.0, 3.0));
  for (int c = 0; c < cabinets; ++c) {
    const double side = rng.Chance(0.5) ? 1.0 : -1.0;
    out.push_back({side * (0.5 * room_width - 0.35), rng.Uniform(1.4, depth - 0.8), 0.5, rng.Uniform(0.8, 1.2),
                   rng.Uniform(1.1, 2.0), false});
  }
  out.push_back({rng.Uniform(-1.2, 1.2), depth - 0.3, 0.3, 0.3, 0.4, true});
  return out;
}

constexpr double kRoomWidth = 4.0, kRoomDepth = 5.0;

int RoomsPerSide(const SceneOptions& o) {
  return std::max(2, static_cast<int>(std::round(o.street_length_m / kRoomWidth)));
}

// Where a room's door starts, from the room's -x wall: the same in every room on the +y side,
// mirrored on the -y side (so that a 180° turn maps a room onto a room), centred on kOfficeIdentical.
double DoorFrom(const SceneOptions& o, double side) {
  const double from = o.kind == SceneOptions::Kind::kOfficeIdentical ? 0.5 * (kRoomWidth - kDoorWidth) : 0.6;
  return side > 0 ? from : kRoomWidth - from - kDoorWidth;
}

}  // namespace

double OfficeRoomFace() { return kHalfCorridor + kWall; }

double OfficeDoorCentre(const SceneOptions& o, double x, double side) {
  const int rooms = RoomsPerSide(o);
  const double half_l = 0.5 * rooms * kRoomWidth;
  const int k = std::clamp(static_cast<int>(std::floor((x + half_l) / kRoomWidth)), 0, rooms - 1);
  return -half_l + k * kRoomWidth + DoorFrom(o, side) + 0.5 * kDoorWidth;
}

void AddOffice(const SceneOptions& o, Scene& s, Rng& rng) {
  const bool identical = o.kind == SceneOptions::Kind::kOfficeIdentical;
  const double room_width = kRoomWidth, depth = kRoomDepth;
  const int rooms = RoomsPerSide(o);
  const double half_l = 0.5 * rooms * room_width;
  const double back = kHalfCorridor + kWall + depth;  // |y| of the outer walls' room face
  Builder b{s, rng, identical};

  // Painted surfaces: almost no reflectance contrast.
  const int paint = s.AddTexture(b.Noisy(0.72f, identical ? 0.004f : 0.012f, 1.5));
  const int floor = s.AddTexture(b.Noisy(0.35f, 0.02f, 0.8));
  const int ceiling = s.AddTexture(SurfaceTexture::Uniform(0.8f));
  const int lamp = s.AddTexture(SurfaceTexture::Uniform(0.95f));
  const int glass = s.AddTexture(SurfaceTexture::Uniform(0.06f));
  const int wood = s.AddTexture(SurfaceTexture::Uniform(0.45f));
  const int grey = s.AddTexture(SurfaceTexture::Uniform(0.55f));
  const double reach = half_l + 1.0;
  s.AddRectangle(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY(), reach, back + 1.0, floor);
  s.AddRectangle(Vec3(0, 0, kCeiling), Vec3::UnitX(), Vec3::UnitY(), reach, back + 1.0, ceiling);

  // The corridor's ends; the rooms' outer walls (with their windows) and the partitions between rooms.
  for (int end : {-1, 1}) Span(s, Vec3(end * half_l - (end > 0 ? 0 : kWall), -back - kWall, 0),
                               Vec3(end * half_l + (end > 0 ? kWall : 0), back + kWall, kCeiling), paint);
  for (int side : {-1, 1}) {
    const double y_out = side * back;
    Span(s, Vec3(-half_l, std::min(y_out, y_out + side * kWall), 0), Vec3(half_l, std::max(y_out, y_out + side * kWall), kCeiling),
         paint);
    for (int k = 1; k < rooms; ++k) {
      const double x = -half_l + k * room_width;
      Span(s, Vec3(x - 0.5 * kWall, std::min(side * (kHalfCorridor + kWall), y_out), 0),
           Vec3(x + 0.5 * kWall, std::max(side * (kHalfCorridor + kWall), y_out), kCeiling), paint);
    }
  }
  if (!identical) {  // the ends differ: a glass door at one, a fire door and an extinguisher at the other
    s.AddRectangle(Vec3(-half_l + 0.01, 0, 1.1), Vec3::UnitY(), Vec3::UnitZ(), 0.8, 1.1, glass);
    Span(s, Vec3(half_l - 0.05, -0.5, 0), Vec3(half_l, 0.5, 2.05), grey);
    s.AddCylinder({half_l - 0.3, 0.75}, 0.09, 0.4, 1.0, s.AddTexture(SurfaceTexture::Uniform(0.3f)));
  }

  // The corridor walls with a door per room, the same place in every room.
  const std::vector<Piece> shared = Furniture(rng, room_width, depth);
  for (int side : {-1, 1}) {
    const double y0 = side * kHalfCorridor, y1 = side * (kHalfCorridor + kWall);
    const double ylo = std::min(y0, y1), yhi = std::max(y0, y1);
    for (int k = 0; k < rooms; ++k) {
      const double x0 = -half_l + k * room_width;
      const double d0 = x0 + DoorFrom(o, side), d1 = d0 + kDoorWidth;
      Span(s, Vec3(x0, ylo, 0), Vec3(d0, yhi, kCeiling), paint);
      Span(s, Vec3(d1, ylo, 0), Vec3(x0 + room_width, yhi, kCeiling), paint);
      Span(s, Vec3(d0, ylo, kDoorHeight), Vec3(d1, yhi, kCeiling), paint);
      // The door leaf, open into the room against its hinge side.
      const double hinge = side > 0 ? d0 : d1, toward = side > 0 ? 1.0 : -1.0;
      Span(s, Vec3(std::min(hinge, hinge + toward * 0.04), std::min(y1, y1 + side * 0.9), 0.01),
           Vec3(std::max(hinge, hinge + toward * 0.04), std::max(y1, y1 + side * 0.9), kDoorHeight - 0.02), wood);
      // The room: window, lights, furniture (a = along +x from the room's centre, b = into the room).
      const double xc = x0 + 0.5 * room_width, y_room = side * (kHalfCorridor + kWall);
      s.AddRectangle(Vec3(xc, side * (back - 0.01), 1.6), Vec3::UnitX(), Vec3::UnitZ(), 1.0, 0.7, glass);
      for (double b : {1.5, 3.6}) Span(s, Vec3(xc - 0.3, y_room + side * b - 0.3, kCeiling - 0.05),
                                       Vec3(xc + 0.3, y_room + side * b + 0.3, kCeiling), lamp);
      const std::vector<Piece> pieces = identical ? shared : Furniture(rng, room_width, depth);
      for (const Piece& p : pieces) {
        const double a = side > 0 ? p.a : -p.a;
        const Vec3 c(xc + a, y_room + side * p.b, 0.0);
        if (p.round) {
          s.AddCylinder(c.head<2>(), 0.5 * p.size_a, 0.0, p.height, grey);
        } else {
          Span(s, c - Vec3(0.5 * p.size_a, 0.5 * p.size_b, 0), c + Vec3(0.5 * p.size_a, 0.5 * p.size_b, p.height),
               p.height > 1.0 && p.size_b > 0.7 ? grey : wood);
        }
      }
    }
    // Notice boards in the corridor (kOffice): a few, on a random wall segment each.
    if (!identical) {
      for (int k = 0; k < rooms; ++k) {
        if (!rng.Chance(0.35)) continue;
        const double x = -half_l + k * room_width + rng.Uniform(2.0, room_width - 0.8);
        const int board = s.AddTexture(b.Poster(static_cast<float>(rng.Uniform(0.4, 0.8))));
        s.AddRectangle(Vec3(x, y0 - side * 0.015, 1.5), Vec3::UnitX(), Vec3::UnitZ(), 0.5, 0.4, board);
      }
    }
  }
  // Ceiling lights along the corridor, symmetric about x = 0.
  const int lights = static_cast<int>(2.0 * half_l / kLightPitch);
  for (int j = 0; j < lights; ++j) {
    const double x = (j - 0.5 * (lights - 1)) * kLightPitch;
    Span(s, Vec3(x - 0.3, -0.3, kCeiling - 0.05), Vec3(x + 0.3, 0.3, kCeiling), lamp);
  }
}

}  // namespace scanreg
