// Sphere targets found in a scan by their geometry (issue 15, item 1): survey spheres of a known
// radius on tripods. Every valid cell gets a surface normal from its grid neighbours a fixed
// metric distance apart (about half the radius, whatever the range); a cell votes for the centre
// r behind it along the normal only when its grid neighbours vote for the same centre (which
// no plane, edge or pole does). Clusters of votes are fitted by least squares with the radius held
// (Gauss-Newton, inliers re-selected) and kept when the fit covers a visible cap of the sphere:
// enough points for the range, spread over at least 45° from the line of sight, few inside.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::georef {

struct SphereTargetOptions {
  double radius_m = 0.0725;  // the spheres' radius (145 mm spheres are common)
  double max_range_m = 60.0;
  int min_points = 12;         // fitted points at least
  double min_coverage = 0.4;   // fitted points / the cells a sphere shows at its range
  double min_cap_deg = 45.0;   // angle from the line of sight the fitted points reach
  double max_rms_fraction = 0.05;  // fit RMS at most this fraction of the radius
  // The centre's standard deviation at most this fraction of the radius (2 mm for 145 mm spheres):
  // a less precise centre is no use as a target, and noise on a wall can mimic a faint sphere.
  double max_sigma_fraction = 0.03;

  Status Validate() const;
};

struct DetectedSphere {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // scanner frame, metres
  double rms_m = 0;      // RMS of |p - c| - r over the fitted points
  int points = 0;        // fitted points
  double coverage = 0;   // points / expected cells at this range
  double sigma_m = 0;    // standard deviation of the centre, from the fit
};

// Spheres sorted by range. An empty list is not an error (no target in the scan). Errors: bad
// options, a scan that is not an organized grid, cancel.
Expected<std::vector<DetectedSphere>> DetectSphereTargets(const Scan& scan, const SphereTargetOptions& options,
                                                          const CancelToken& cancel);

// Least-squares centre of a sphere of known radius through the points (Gauss-Newton from `start`),
// with the RMS of the distances to the surface. For tests and the GUI's picked targets.
Eigen::Vector3d FitSphereCenter(const std::vector<Eigen::Vector3d>& points, double radius, const Eigen::Vector3d& start,
                                double* rms_m = nullptr);

}  // namespace scanreg::georef
