// Refining one pair from a start pose, without features: the fine step (dense ICP, then EM or
// projective ICP when the reach is wide), a check that it did not walk away, and the link's status
// from the evidence every method shares. Refinement from the current poses (refine_project.h)
// runs it on every link; the GUI runs it on one pair (refine from the current pose, picked points).
#pragma once

#include <Eigen/Geometry>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_pair.h"

namespace scanreg::pipeline {

// The fine step's scale follows the reach (options.overlap_distance_m): dense ICP samples of at
// most half of it and a correspondence schedule of 1, 1/2 and 1/4 of it.
RegisterOptions ScaledToReach(RegisterOptions options);

// Refines child to parent from `initial` with options (already ScaledToReach) and classifies the
// link from the shared evidence measured at evidence_m (the data's overlap distance; the reach,
// options.overlap_distance_m, may be larger). A refinement that moves the child more than twice the
// reach has diverged and fails. link.method: "none+<fine>".
io::LinkRecord RefinePair(const PreparedScan& parent, const PreparedScan& child, const Eigen::Isometry3d& initial,
                          const RegisterOptions& options, double evidence_m, const CancelToken& cancel);

// One pair on its own: lengths resolved from both scans (scale_defaults.h), samples prepared, and
// RefinePair with a reach of reach_m (at least the data's overlap distance; 0: how far apart the
// scans' world_from_scan put them, StartDistance in scale_defaults.h). Errors: invalid
// options, the keypoints fine method, a scan without valid points, cancel.
Expected<io::LinkRecord> RefinePairFromPose(const Scan& parent, const Scan& child, const Eigen::Isometry3d& initial,
                                            const RegisterOptions& options, double reach_m,
                                            const CancelToken& cancel);

}  // namespace scanreg::pipeline
