// The pairwise fine step of the pipeline for every FineMethod that needs no features: dense
// point-to-plane ICP on voxel samples, S's EM alignment and projective ICP [15] on the range
// images (core/registration/em_align.h). Used after the image-based coarse step and, with
// --coarse none, from the project's current poses.
#pragma once

#include <Eigen/Geometry>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_options.h"
#include "core/registration/em_align.h"

namespace scanreg::pipeline {

struct PreparedScan;

// EM options for the pipeline: sigma = options.range_sigma_m, correspondences farther than
// options.overlap_distance_m dropped, occlusion outliers rejected (MAD factor 3), the child
// subsampled to about 10,000 vertices; method from options.fine (kEm or kProjectiveIcp).
EmOptions PipelineEmOptions(const RegisterOptions& options, const Scan& child);

struct FineResult {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  int iterations = 0;
  bool converged = false;
};

// Refines parent_from_child with options.fine (kDense, kEm or kProjectiveIcp; kKeypoints needs the
// feature correspondences and is an error here). Errors: no overlap at the start, cancel.
Expected<FineResult> AlignFine(const PreparedScan& parent, const PreparedScan& child,
                               const Eigen::Isometry3d& initial_parent_from_child, const RegisterOptions& options,
                               const CancelToken& cancel);

}  // namespace scanreg::pipeline
