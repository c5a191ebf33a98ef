// A simulated scan project: stations along the street of MakeScene, as a surveyor would place them
// (W §1: 11 upright scans ~5 m apart). Scans arrive unregistered (world_from_scan = Identity); the
// true poses are their reference poses.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/simulate/scanner.h"
#include "core/simulate/scene.h"
#include "core/simulate/traffic.h"

namespace scanreg {

struct SimulatedProjectOptions {
  int stations = 11;         // scans along the street
  double spacing_m = 5.0;    // metres between consecutive stations (before jitter)
  ScannerOptions scanner;    // per-scan noise seed is derived from scanner.seed, seed and the station
  SceneOptions scene;        // street length is extended when the stations need more room
  std::uint64_t seed = 1;    // station positions, headings, tilts and per-scan noise
  double max_tilt_deg = 0.5;  // degrees: random tilt of each station from upright
  bool add_far_station = false;  // one extra station at a separate site > 1 km away (no overlap)
  TrafficOptions traffic;        // moving vehicles and pedestrians, placed anew for each scan
  // Survey sphere targets on tripods, spread along the stations on both sides of the street
  // (scene.sphere_target_radius_m), named "T1", "T2", ... in order along +x.
  int sphere_targets = 0;
  // Checkerboard targets stuck on the façades (2 mm proud of the wall), spread along the stations on
  // both sides, 1.5-2.5 m up, named "C1", "C2", ... in order along +x.
  int checker_targets = 0;
  double checker_size_m = 0.2;  // side of the 2 x 2 pattern
  double control_noise_m = 0.002;  // sigma per axis of the simulated control coordinates (total station / GNSS)
  // Where the project sits in the survey's coordinate system (a national grid, UTM): the scans'
  // reference poses and the targets' control coordinates are control_from_world times the scene's.
  Eigen::Isometry3d control_from_world = Eigen::Isometry3d::Identity();

  Status Validate() const;
};

struct SimulatedTarget {
  std::string name;
  std::string kind = "sphere";  // "sphere" or "checker"
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // checkerboards: the board's normal (scene frame)
  Eigen::Vector3d world = Eigen::Vector3d::Zero();    // centre in the scene
  Eigen::Vector3d control = Eigen::Vector3d::Zero();  // control_from_world * world
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();  // control plus noise of control_noise_m per axis
};

// The targets SimulateProject places: spheres, then checkerboards (empty when there are none).
std::vector<SimulatedTarget> SimulatedTargets(const SimulatedProjectOptions& options);

// Scans named "s01", "s02", ... in station order along +x; the far station, if any, comes last.
// Reference poses are control_from_world * the true station poses.
// moving_cells, when given, receives per scan the cells that returned from moving objects.
Expected<std::vector<Scan>> SimulateProject(const SimulatedProjectOptions& options, ProgressSink& progress,
                                            const CancelToken& cancel,
                                            std::vector<std::vector<std::uint8_t>>* moving_cells = nullptr);

// The same one scan at a time, each handed to `sink` as soon as it is made (with its moving cells when
// asked for), so that a project of 100+ scans never sits in memory at once. A sink's error stops it.
using ScanSink = std::function<Status(Scan&&, std::vector<std::uint8_t>&& moving_cells)>;
Status SimulateProjectScans(const SimulatedProjectOptions& options, const ScanSink& sink, ProgressSink& progress,
                            const CancelToken& cancel, bool with_moving_cells = false);

// The true scanner poses SimulateProject uses (no scanning), in the same order.
std::vector<Eigen::Isometry3d> SimulatedStationPoses(const SimulatedProjectOptions& options);

}  // namespace scanreg
