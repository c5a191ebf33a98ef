// Plan-view alignment of levelled scans (issue 11, item 3: "a solver that uses what TLS gives"):
// with both scans levelled only a heading and a translation are unknown. Walls and poles (samples
// whose normal is near horizontal) seen from above form a map; the heading comes from the
// circular correlation of the wall-normal direction histograms, the horizontal translation from
// the 2D cross-correlation (FFT) of the two wall maps, the height from the ground under each
// scanner. No feature correspondence is needed, so sparse stations, low resolution and scans
// without reflectance get pose hypotheses that the fine step and the surface evidence then judge.
//
// The map holds every wall the scan saw, however far: a return is on a wall where the next one up
// its column stands above it, and two neighbouring columns' returns on one straight wall are joined
// by the piece of wall between them. The features'
// samples alone hold only the walls near the scanner — far walls, seen at a grazing angle, are
// sampled a metre apart and get no normal — so a map of them rewards poses that put both scanners
// on one spot (measured on an office corridor, stations 8 m apart, each seeing the whole 36 m
// corridor: the samples' walls reached 6 m either way, and the pose on one spot turned 180° beat
// the true one; issue 38).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/geometry/scan.h"
#include "core/registration/geometric_features.h"

namespace scanreg {

struct PlanView {
  bool usable = false;                      // levelled, with enough walls
  double cell_m = 0.0;                      // map cell size
  std::vector<Eigen::Vector2d> wall_xy;     // wall cells (or samples), levelled frame, within the map radius
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> wall_runs;  // wall between neighbouring columns' returns
  std::vector<double> wall_azimuth;         // the feature samples' wall normals' azimuth, radians (the heading)
  double ground_z = 0.0;                    // median height of the ground samples, levelled frame
};

struct PlanOptions {
  double radius_m = 60.0;     // walls farther than this from the scanner are left out of the map
  double cell_voxels = 2.0;   // map cell, in voxels of the geometric features
  int max_headings = 4;       // heading peaks tried (each also turned by 180°)
  int max_hypotheses = 3;     // poses returned, best correlation first
  double min_relative_score = 0.8;  // poses correlating less than this x the best are not returned
  double max_wall_run_m = 4.0;  // neighbouring returns farther apart are not joined as one wall
};

// From the features' wall samples alone.
PlanView MakePlanView(const GeometricFeatures& features, const PlanOptions& options = {});
// With every wall the scan's points show (the scan the features were found on).
PlanView MakePlanView(const GeometricFeatures& features, const Scan& scan, const PlanOptions& options = {});

struct PlanHypothesis {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();  // levelled frames
  double score = 0.0;  // normalised correlation of the wall maps at this pose, [0, 1]
};

// Distinct poses (levelled parent from levelled child), best first.
std::vector<PlanHypothesis> PlanHypotheses(const PlanView& parent, const PlanView& child,
                                           const PlanOptions& options = {});

}  // namespace scanreg
