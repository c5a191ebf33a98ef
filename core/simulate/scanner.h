// A simulated terrestrial laser scanner: a panoramic grid of rays cast into a Scene. Models the
// error sources that make real scans hard for registration: Gaussian range noise along the line
// of sight (S §3), reflectance depending on albedo, incidence and range, weak returns lost, no
// return from the sky or beyond max range, occlusion, and mixed pixels at depth edges.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/simulate/scene.h"

namespace scanreg {

struct ScannerOptions {
  // Grid: W's Riegl LMS-Z360 at 0.12° steps (SPEC §1). Column c looks at azimuth
  // -pi + (c + 0.5) * 2 pi / cols; row r at elevation max - (r + 0.5) * (max - min) / rows.
  int cols = 3000;                   // azimuth samples over 360°
  int rows = 750;                    // elevation samples
  double elevation_min_deg = -40.0;  // degrees, bottom of the last row
  double elevation_max_deg = 50.0;   // degrees, top of row 0
  double min_range_m = 1.0;          // metres; nearer surfaces give no return
  double max_range_m = 200.0;        // metres; farther surfaces (and the sky) give no return
  double range_noise_m = 0.012;      // sigma of Gaussian range noise along the line of sight, metres
  double range_noise_per_m = 0.0;    // added to that sigma per metre of range (1e-4: +1 cm at 100 m)
  double angle_noise_deg = 0.0;      // sigma of Gaussian noise of each beam's azimuth and elevation, degrees
  double reflectance_noise = 0.02;   // sigma of additive Gaussian reflectance noise, reflectance units
  bool reflectance = true;           // false: every return has reflectance 0.5 (no usable intensity)
  double falloff_range_m = 60.0;     // metres at which the returned intensity has halved (1 / (1 + r / this))
  double min_return_signal = 0.002;  // albedo x cos(incidence) x fall-off below this is lost (no return)
  bool mixed_pixels = true;          // blend ranges across depth edges, as real beams with a footprint do
  double mixed_pixel_probability = 0.5;  // chance that a cell at a depth edge returns a blended range
  double mixed_pixel_min_jump_m = 0.3;   // metres: range jump to a neighbour on another surface = depth edge
  std::uint64_t seed = 1;            // all noise is a function of (seed, cell): thread-count independent

  Status Validate() const;
};

// Simulates one scan from the scanner pose world_from_scanner. The returned Scan has points in the
// scanner frame, scan.angles filled, world_from_scan = Identity (unregistered) and
// reference_world_from_scan = world_from_scanner. Cancellation is checked once per row.
// moving_cells, when given, receives 1 for each cell whose return came from a moving object
// (Scene::IsMoving), 0 elsewhere: the truth for moving-object detection.
Expected<Scan> SimulateScan(const Scene& scene, const Eigen::Isometry3d& world_from_scanner,
                            const ScannerOptions& options, std::string name, ProgressSink& progress,
                            const CancelToken& cancel, std::vector<std::uint8_t>* moving_cells = nullptr);

}  // namespace scanreg
