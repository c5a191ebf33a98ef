#include "core/simulate/project_sim.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <utility>

#include "core/simulate/random.h"
#include "core/simulate/scene_builder.h"

namespace scanreg {
namespace {

constexpr double kDeg = M_PI / 180.0;

double SpanOf(const SimulatedProjectOptions& o) { return (o.stations - 1) * o.spacing_m; }

bool IsCity(const SimulatedProjectOptions& o) { return o.scene.kind == SceneOptions::Kind::kCity; }

// kCity: station positions every spacing_m along the streets in walking order, none within half a
// spacing of an earlier one (crossings are scanned once), at most o.stations of them.
std::vector<Eigen::Vector3d> CityStations(const SimulatedProjectOptions& o, const SceneOptions& city, sim::Rng& rng) {
  const double lateral = std::min(1.5, 0.2 * o.spacing_m);
  // Each block's length is split evenly at no more than the spacing, so a station stands at every
  // crossing (where the surveyor sees along both streets).
  const double pitch = CityPitch(city), step = pitch / std::ceil(pitch / o.spacing_m - 1e-9);
  std::vector<Eigen::Vector3d> out;
  for (const StreetLeg& leg : CityStreets(city)) {
    const Eigen::Vector3d a = (leg.to - leg.from).normalized(), left = Eigen::Vector3d::UnitZ().cross(a);
    const double length = (leg.to - leg.from).norm();
    for (double u = 0.0; u <= length + 1e-6 && static_cast<int>(out.size()) < o.stations; u += step) {
      const Eigen::Vector3d at = leg.from + u * a;
      bool near = false;
      for (const Eigen::Vector3d& q : out) near |= (q - at).head<2>().norm() < 0.5 * o.spacing_m;
      if (near) continue;
      out.push_back(at + rng.Uniform(-0.1, 0.1) * o.spacing_m * a + rng.Uniform(-lateral, lateral) * left +
                    Eigen::Vector3d(0, 0, rng.Uniform(1.5, 2.0)));
    }
  }
  return out;
}

bool IsOfficeProject(const SimulatedProjectOptions& o) { return IsOffice(o.scene.kind); }

// Office floors: the corridor holds half the stations (rounded up) spacing_m apart with 3 m to spare
// at each end, at least 36 m.
double OfficeLength(const SimulatedProjectOptions& o) {
  const int corridor = (o.stations + 1) / 2;
  return std::max(36.0, (corridor - 1) * o.spacing_m + 6.0);
}

// Office floors: stations in walking order: a corridor station, then one in the room whose door is
// nearest to it (alternating sides), 1.2-1.7 m inside, and so on; the corridor stations spacing_m
// apart along its axis. Furniture stands clear of the room stations (scene_office.cc).
std::vector<Eigen::Vector3d> OfficeStations(const SimulatedProjectOptions& o, sim::Rng& rng) {
  const int corridor = (o.stations + 1) / 2;
  std::vector<Eigen::Vector3d> out;
  for (int i = 0; i < corridor; ++i) {
    const double x = (i - 0.5 * (corridor - 1)) * o.spacing_m + rng.Uniform(-0.1, 0.1) * std::min(o.spacing_m, 4.0);
    out.emplace_back(x, rng.Uniform(-0.3, 0.3), rng.Uniform(1.4, 1.7));
    if (static_cast<int>(out.size()) == o.stations) break;
    const double side = i % 2 == 0 ? 1.0 : -1.0;
    SceneOptions floor = o.scene;
    floor.street_length_m = OfficeLength(o);
    const double door = OfficeDoorCentre(floor, x, side);
    out.emplace_back(door + rng.Uniform(-0.4, 0.4), side * (OfficeRoomFace() + rng.Uniform(1.2, 1.7)),
                     rng.Uniform(1.4, 1.7));
  }
  return out;
}

// kCity: the smallest grid of blocks (widening alternately) whose streets hold every station, and
// never smaller than the options ask; nullopt when even 10 x 10 blocks do not.
std::optional<SceneOptions> CityFor(const SimulatedProjectOptions& o) {
  SceneOptions city = o.scene;
  for (int grow = 0; grow < 40; ++grow) {
    sim::Rng rng(0);
    if (static_cast<int>(CityStations(o, city, rng).size()) >= o.stations) return city;
    if (city.city_blocks_x <= city.city_blocks_y) ++city.city_blocks_x;
    else ++city.city_blocks_y;
    if (city.city_blocks_x > 10) return std::nullopt;
  }
  return std::nullopt;
}

// The scene the project scans: the street is lengthened to hold every station with 30 m to spare;
// a city grows to hold them.
SceneOptions ProjectScene(const SimulatedProjectOptions& o) {
  SceneOptions s = IsCity(o) ? CityFor(o).value_or(o.scene) : o.scene;
  s.street_length_m = IsOfficeProject(o) ? OfficeLength(o) : std::max(s.street_length_m, SpanOf(o) + 60.0);
  s.far_site = s.far_site || o.add_far_station;
  for (const SimulatedTarget& t : SimulatedTargets(o)) {
    if (t.kind == "sphere") s.sphere_targets.push_back(t.world);
    else s.checker_targets.push_back({t.world, t.normal, o.checker_size_m});
  }
  return s;
}

Eigen::Isometry3d StationPose(sim::Rng& rng, const Eigen::Vector3d& position, double max_tilt_rad) {
  const double heading = rng.Uniform(-M_PI, M_PI);
  const double tilt_axis = rng.Uniform(-M_PI, M_PI), tilt = max_tilt_rad * std::sqrt(rng.Uniform());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = position;
  pose.linear() = (Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(tilt_axis), std::sin(tilt_axis), 0.0)) *
                   Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()))
                      .toRotationMatrix();
  return pose;
}

}  // namespace

Status SimulatedProjectOptions::Validate() const {
  if (stations < 1 || stations > 200)
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: " + std::to_string(stations) + " stations; use between 1 and 200");
  if (!(spacing_m >= 0.5 && spacing_m <= 50.0))
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: station spacing " + std::to_string(spacing_m) + " m is outside [0.5, 50] m");
  if (!(max_tilt_deg >= 0.0 && max_tilt_deg <= 20.0))
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: max tilt " + std::to_string(max_tilt_deg) + "° is outside [0, 20]°");
  if (IsOfficeProject(*this)) {
    if (sphere_targets > 0 || checker_targets > 0 || add_far_station || traffic.vehicles > 0 || traffic.pedestrians > 0)
      return MakeError(ErrorCode::kInvalidArgument,
                       "project: targets, traffic and the far station are simulated on the street scene only, not "
                       "on the office floor");
    if (OfficeLength(*this) > 400.0)
      return MakeError(ErrorCode::kInvalidArgument, "project: the office corridor would be " +
                                                        std::to_string(OfficeLength(*this)) +
                                                        " m long; reduce the stations or the spacing (max 400 m)");
  } else if (IsCity(*this)) {
    if (sphere_targets > 0 || checker_targets > 0 || add_far_station || traffic.vehicles > 0 || traffic.pedestrians > 0)
      return MakeError(ErrorCode::kInvalidArgument,
                       "project: targets, traffic and the far station are simulated on the street scene only, not "
                       "in the city");
    if (!CityFor(*this))
      return MakeError(ErrorCode::kInvalidArgument, "project: " + std::to_string(stations) + " stations " +
                                                        std::to_string(spacing_m) +
                                                        " m apart do not fit in a city of 10 x 10 blocks; widen the spacing");
  } else if (SpanOf(*this) > 900.0)
    return MakeError(ErrorCode::kInvalidArgument, "project: stations span " + std::to_string(SpanOf(*this)) +
                                                      " m; reduce the stations or the spacing (max 900 m)");
  if (!(traffic.vehicles >= 0 && traffic.vehicles <= 500 && traffic.pedestrians >= 0 && traffic.pedestrians <= 500))
    return MakeError(ErrorCode::kInvalidArgument, "project: traffic must be 0 to 500 vehicles and pedestrians per scan");
  if (!(traffic.reach_m > 0.0 && traffic.reach_m <= 500.0))
    return MakeError(ErrorCode::kInvalidArgument, "project: traffic reach must be in (0, 500] m");
  if (sphere_targets < 0 || sphere_targets > 1000)
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: " + std::to_string(sphere_targets) + " sphere targets; use between 0 and 1000");
  if (checker_targets < 0 || checker_targets > 1000)
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: " + std::to_string(checker_targets) + " checkerboard targets; use between 0 and 1000");
  if (!(checker_size_m >= 0.05 && checker_size_m <= 1.0))
    return MakeError(ErrorCode::kInvalidArgument,
                     "project: checkerboard size " + std::to_string(checker_size_m) + " m is outside [0.05, 1] m");
  if (!(control_noise_m >= 0 && control_noise_m <= 1))
    return MakeError(ErrorCode::kInvalidArgument, "project: control noise must be in [0, 1] m");
  if (!control_from_world.matrix().allFinite() ||
      !(control_from_world.linear().transpose() * control_from_world.linear()).isIdentity(1e-9))
    return MakeError(ErrorCode::kInvalidArgument, "project: control_from_world must be finite and rigid");
  if (Status s = scanner.Validate(); !s) return s;
  return scene.Validate();
}

std::vector<Eigen::Isometry3d> SimulatedStationPoses(const SimulatedProjectOptions& o) {
  sim::Rng rng(sim::Hash(o.seed, 0x57a7));
  if (IsCity(o)) {
    const std::optional<SceneOptions> city = CityFor(o);
    std::vector<Eigen::Isometry3d> poses;
    if (!city) return poses;
    sim::Rng place(sim::Hash(o.seed, 0xc17));
    for (const Eigen::Vector3d& p : CityStations(o, *city, place))
      poses.push_back(StationPose(rng, p, o.max_tilt_deg * kDeg));
    return poses;
  }
  if (IsOfficeProject(o)) {
    std::vector<Eigen::Isometry3d> poses;
    sim::Rng place(sim::Hash(o.seed, 0x0ff1ce));
    for (const Eigen::Vector3d& p : OfficeStations(o, place)) poses.push_back(StationPose(rng, p, o.max_tilt_deg * kDeg));
    return poses;
  }
  const double lateral = std::min(1.5, 0.2 * o.spacing_m);
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < o.stations; ++i) {
    const double x = (i - 0.5 * (o.stations - 1)) * o.spacing_m + rng.Uniform(-0.1, 0.1) * o.spacing_m;
    const Eigen::Vector3d position(x, rng.Uniform(-lateral, lateral), rng.Uniform(1.5, 2.0));
    poses.push_back(StationPose(rng, position, o.max_tilt_deg * kDeg));
  }
  if (o.add_far_station) {
    const Eigen::Vector3d c = FarSiteCenter();
    poses.push_back(StationPose(rng, c + Eigen::Vector3d(rng.Uniform(-3, 3), rng.Uniform(-3, 3), 1.7),
                                o.max_tilt_deg * kDeg));
  }
  return poses;
}

namespace {

// Where a horizontal ray from the street's centre line meets a façade that is flat for a board
// around the hit (every probe ray lands on the same plane): the board's centre 2 mm proud of the
// wall, and the wall's normal. Tries further along x when a pole, tree or window is in the way.
std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> PlaceOnWall(const Scene& walls, double x, double side,
                                                                      double height, double size) {
  for (int attempt = 0; attempt < 40; ++attempt) {
    const double xa = x + (attempt % 2 == 0 ? 1 : -1) * 0.35 * ((attempt + 1) / 2);
    const Eigen::Vector3d origin(xa, 0.0, height), dir(0.0, side, 0.0);
    const auto hit = walls.Intersect(origin, dir, 60.0);
    if (!hit || std::abs(hit->normal.z()) > 0.02) continue;
    const Eigen::Vector3d p = origin + hit->range * dir, n = hit->normal;
    const Eigen::Vector3d u = Eigen::Vector3d::UnitZ().cross(n).normalized(), v = n.cross(u);
    bool flat = true;
    for (int k = 0; k < 8 && flat; ++k) {
      const double a = k * M_PI / 4;
      const Eigen::Vector3d q = p + 0.8 * size * (std::cos(a) * u + std::sin(a) * v) + 0.5 * n;
      const auto h = walls.Intersect(q, -n, 1.0);
      flat = h && std::abs(h->range - 0.5) < 0.002 && std::abs(h->albedo - hit->albedo) < 0.3;
    }
    if (flat) return std::make_pair(Eigen::Vector3d(p + 0.002 * n), n);
  }
  return std::nullopt;
}

}  // namespace

std::vector<SimulatedTarget> SimulatedTargets(const SimulatedProjectOptions& o) {
  std::vector<SimulatedTarget> targets;
  if (o.sphere_targets <= 0 && o.checker_targets <= 0) return targets;
  sim::Rng rng(sim::Hash(o.seed, 0x7a67));
  // Along the stations (and a little beyond the ends), alternating sides on the road between the
  // scanners' lane and the parked cars, at tripod heights.
  const double span = SpanOf(o) + o.spacing_m, side_y = std::min(2.6, o.scene.street_half_width_m - 5.5);
  for (int k = 0; k < o.sphere_targets; ++k) {
    const double f = o.sphere_targets == 1 ? 0.5 : double(k) / (o.sphere_targets - 1);
    SimulatedTarget t;
    t.name = "T" + std::to_string(k + 1);
    t.world = Eigen::Vector3d((f - 0.5) * span + rng.Uniform(-0.5, 0.5), (k % 2 == 0 ? 1 : -1) * side_y + rng.Uniform(-0.3, 0.3),
                              rng.Uniform(1.2, 1.7));
    t.control = o.control_from_world * t.world;
    t.measured = t.control + o.control_noise_m * Eigen::Vector3d(rng.Gaussian(), rng.Gaussian(), rng.Gaussian());
    targets.push_back(t);
  }
  if (o.checker_targets <= 0) return targets;
  SceneOptions bare = o.scene;  // the street the boards are stuck on (targets do not move walls)
  bare.street_length_m = std::max(bare.street_length_m, SpanOf(o) + 60.0);
  bare.sphere_targets.clear();
  bare.checker_targets.clear();
  const Scene walls = MakeScene(bare);
  sim::Rng crng(sim::Hash(o.seed, 0xc4ec));
  for (int k = 0; k < o.checker_targets; ++k) {
    const double f = o.checker_targets == 1 ? 0.5 : double(k) / (o.checker_targets - 1);
    const double x = (f - 0.5) * span + crng.Uniform(-0.5, 0.5), height = crng.Uniform(1.5, 2.5);
    const auto placed = PlaceOnWall(walls, x, k % 2 == 0 ? -1.0 : 1.0, height, o.checker_size_m);
    if (!placed) continue;  // no flat wall near this spot: one target fewer
    SimulatedTarget t;
    t.name = "C" + std::to_string(k + 1);
    t.kind = "checker";
    t.world = placed->first;
    t.normal = placed->second;
    t.control = o.control_from_world * t.world;
    t.measured = t.control + o.control_noise_m * Eigen::Vector3d(crng.Gaussian(), crng.Gaussian(), crng.Gaussian());
    targets.push_back(t);
  }
  return targets;
}

Expected<std::vector<Scan>> SimulateProject(const SimulatedProjectOptions& options, ProgressSink& progress,
                                            const CancelToken& cancel,
                                            std::vector<std::vector<std::uint8_t>>* moving_cells) {
  std::vector<Scan> scans;
  if (moving_cells) moving_cells->clear();
  const Status s = SimulateProjectScans(
      options,
      [&](Scan&& scan, std::vector<std::uint8_t>&& moving) {
        scans.push_back(std::move(scan));
        if (moving_cells) moving_cells->push_back(std::move(moving));
        return Status::Ok();
      },
      progress, cancel, moving_cells != nullptr);
  if (!s) return s.error();
  return scans;
}

Status SimulateProjectScans(const SimulatedProjectOptions& options, const ScanSink& sink, ProgressSink& progress,
                            const CancelToken& cancel, bool with_moving_cells) {
  if (Status s = options.Validate(); !s) return s;
  progress.Report(0.0, "building the scene");
  const SceneOptions street = ProjectScene(options);
  const Scene static_scene = MakeScene(street);
  const bool traffic = options.traffic.vehicles > 0 || options.traffic.pedestrians > 0;
  const std::vector<Eigen::Isometry3d> poses = SimulatedStationPoses(options);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "project simulation cancelled");
    char name[32];  // s01 ... s99, or s001 ... from 100 stations on (names sort in station order)
    std::snprintf(name, sizeof(name), poses.size() >= 100 ? "s%03zu" : "s%02zu", i + 1);
    ScannerOptions scanner = options.scanner;
    scanner.seed = sim::Hash(options.scanner.seed, options.seed, i);
    const double n = static_cast<double>(poses.size());
    SubProgress sub(progress, i / n, (i + 1) / n);
    Scene with_traffic;
    if (traffic) {  // the street as this scan saw it: its own vehicles and people
      with_traffic = static_scene;
      with_traffic.set_first_moving(
          AddTraffic(with_traffic, street, poses[i].translation(), options.traffic, sim::Hash(options.seed, i, 0x7af)));
      with_traffic.Build();
    }
    std::vector<std::uint8_t> moving;
    Expected<Scan> scan = SimulateScan(traffic ? with_traffic : static_scene, poses[i], scanner, name, sub, cancel,
                                       with_moving_cells ? &moving : nullptr);
    if (!scan) return scan.error();
    scan->reference_world_from_scan = options.control_from_world * poses[i];
    if (Status s = sink(std::move(scan).value(), std::move(moving)); !s) return s;
  }
  return Status::Ok();
}

}  // namespace scanreg
