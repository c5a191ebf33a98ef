// Plan-view alignment of levelled scans (issue 11, item 3: "a solver that uses what TLS gives"):
// with both scans levelled only a heading and a translation are unknown. Walls and poles (samples
// whose normal is near horizontal) seen from above form a map; the heading comes from the
// circular correlation of the wall-normal direction histograms, the horizontal translation from
// the 2D cross-correlation (FFT) of the two wall maps, the height from the ground under each
// scanner. No feature correspondence is needed, so sparse stations, low resolution and scans
// without reflectance get pose hypotheses that the fine step and the surface evidence then judge.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/registration/geometric_features.h"

namespace scanreg {

struct PlanView {
  bool usable = false;                      // levelled, with enough walls
  double cell_m = 0.0;                      // map cell size
  std::vector<Eigen::Vector2d> wall_xy;     // wall samples, levelled frame, within the map radius
  std::vector<double> wall_azimuth;         // their normals' azimuth, radians
  double ground_z = 0.0;                    // median height of the ground samples, levelled frame
};

struct PlanOptions {
  double radius_m = 60.0;     // walls farther than this from the scanner are left out of the map
  double cell_voxels = 2.0;   // map cell, in voxels of the geometric features
  int max_headings = 4;       // heading peaks tried (each also turned by 180°)
  int max_hypotheses = 3;     // poses returned, best correlation first
  double min_relative_score = 0.8;  // poses correlating less than this x the best are not returned
};

PlanView MakePlanView(const GeometricFeatures& features, const PlanOptions& options = {});

struct PlanHypothesis {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();  // levelled frames
  double score = 0.0;  // normalised correlation of the wall maps at this pose, [0, 1]
};

// Distinct poses (levelled parent from levelled child), best first.
std::vector<PlanHypothesis> PlanHypotheses(const PlanView& parent, const PlanView& child,
                                           const PlanOptions& options = {});

}  // namespace scanreg
