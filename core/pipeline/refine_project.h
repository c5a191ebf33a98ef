// Registration from the scans' current poses, without features (`scanreg-cli register --coarse
// none`): the way range scans without reflectance, like the Stanford scans with their .conf poses,
// or a project registered before, are refined. Links are the pairs whose surfaces overlap at the
// current poses: a maximum spanning tree over the overlap is refined pairwise with the fine method
// (EM, projective ICP or dense ICP) and chained from the root; with options.global every other
// overlapping pair is registered too and a pose graph solves all links.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {

// Same contract as RegisterScans (register_project.h). The overlap of child j on parent i is the
// fraction of j's voxel samples within options.overlap_distance_m of i's samples at the current
// poses; pairs below thresholds.min_overlap are not linked. options.overlap_distance_m also sets
// the scale of the fine step (dense ICP voxel and distance schedule, EM correspondence limit), so
// it should be a few times the current pose error.
Expected<ProjectRegistration> RegisterFromCurrentPoses(const std::vector<Scan>& scans, const UserChoices& user,
                                                       const RegisterOptions& options, ProgressSink& progress,
                                                       const CancelToken& cancel);

}  // namespace scanreg::pipeline
