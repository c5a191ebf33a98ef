// Manual alignment (issue 14, item 2): when the automatic registration leaves a scan out, the user
// picks the same points in both scans; the pose from those points is only a start, refined with the
// fine step like any other link and judged by the same evidence. The result is a normal link that
// keeps its picked points (io::LinkRecord::picked) and says where it came from (method "picked+…").
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"

namespace scanreg::pipeline {

struct PickedFit {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  std::vector<double> residual_m;  // per pair: |parent − parent_from_child · child|
  double rms_m = 0.0;
  bool levelled = false;  // heading and translation only
};

// The pose from picked pairs (each point in its own scan's frame). levelled (both scans level,
// z up): heading and translation, from 2 pairs or more; otherwise a full rigid fit from 3 pairs or
// more that are not collinear. Errors name what is missing: too few pairs, a non-finite point,
// points that are coincident or collinear (pick points farther apart, not on one line).
Expected<PickedFit> FitPickedPoints(const std::vector<io::PickedPoint>& pairs, bool levelled);

// How far the refinement reaches from a fit: three times its largest residual, at least a hundredth
// and at most a fifth of the picked points' spread (their largest distance from their centroid).
double PickedReach(const PickedFit& fit, const std::vector<io::PickedPoint>& pairs);

// Fits the picked pairs, then refines child to parent from the fit (RefinePairFromPose, reach
// PickedReach). A refinement that fails is not an error: the link says why (status kFailed).
// Errors: the fit's errors; a residual above a tenth of the spread (a pick on the wrong point: it is
// named); invalid options; cancel.
Expected<io::LinkRecord> AlignFromPickedPoints(const Scan& parent, const Scan& child,
                                               const std::vector<io::PickedPoint>& pairs, bool levelled,
                                               const RegisterOptions& options, const CancelToken& cancel);

}  // namespace scanreg::pipeline
