// Moving objects for the TLS simulator: vehicles (cars, vans, a bus) on the road and pedestrians on
// the sidewalks and crossing, placed anew for every scan as on a real street with traffic. A scan's
// scene is the static street plus its own traffic; the objects of other scans are not there.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>

#include "core/simulate/scene.h"

namespace scanreg {

struct TrafficOptions {
  int vehicles = 0;     // vehicles on the road within reach of the station (1 in 8 a van, 1 in 16 a bus)
  int pedestrians = 0;  // people on the sidewalks (1 in 4 crossing the road)
  double reach_m = 45.0;  // metres along the street either side of the station where they are placed
};

// Adds `options`' objects to `scene` (the static street of MakeScene(street)) around `station`,
// keeping 1.5 m clear of the scanner. Returns the index of the first moving primitive: primitives
// from there on are traffic. Call scene.Build() afterwards.
int AddTraffic(Scene& scene, const SceneOptions& street, const Eigen::Vector3d& station, const TrafficOptions& options,
               std::uint64_t seed);

}  // namespace scanreg
