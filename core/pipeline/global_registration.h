// Global registration of a pairwise result (issue 4): a pose graph over every accepted link (tree
// links and loop checks), Cauchy kernel, root fixed (core/registration/pose_graph.h). Scans left
// unregistered stay out of the graph. Shared by the feature-based and the current-pose
// registration.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {

// Re-solves result->scans[i].world_from_scan of the registered scans from result->links (failed
// links skipped) and fills result->global_links. Errors: built without Ceres (kUnsupported),
// cancel.
Status RunGlobalRegistration(const std::vector<Scan>& scans, const CancelToken& cancel, ProjectRegistration* result);

}  // namespace scanreg::pipeline
