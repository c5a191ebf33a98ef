// One pair of scans examined on its own (the GUI's pair view and pair panel): the features of both
// scans, their matches both ways as the project registration uses them, RegisterPair with the
// chosen methods, which matches the coarse RANSAC kept, the errors against the reference poses
// and each scan's distance to the other's surface at the result (for a coloured overlay).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/features/matching.h"
#include "core/features/sift.h"
#include "core/geometry/scan.h"
#include "core/geometry/transform.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_pair.h"

namespace scanreg::pipeline {

struct PairInspection {
  ScanFeatures parent_features, child_features;
  std::vector<FeatureMatch> matches;        // query = parent keypoint, train = child keypoint
  std::vector<std::uint8_t> coarse_inlier;  // per match: 1 if the coarse RANSAC kept it
  PairResult result;                        // result.link: evidence, status, reason, parent_from_child
  // Against the reference poses (both scans need one): the relative pose after fine and after coarse.
  std::optional<PoseError> reference_error, coarse_reference_error;
  // The overlay: points of both scans in the parent's frame at the result, each with its
  // distance to the other scan's surface in metres (negative: no surface within the overlap
  // distance, i.e. outside the overlap).
  std::vector<Eigen::Vector3f> parent_points, child_points;
  std::vector<float> parent_distance_m, child_distance_m;
};

struct InspectOptions {
  bool overlay = true;         // compute the overlay points and distances
  int overlay_points = 60000;  // per scan, evenly thinned from the valid points
};

// Errors: a scan without valid points or invalid options (kInvalidArgument), cancel (kCancelled).
// A registration that fails is not an error: result.link says why (status kFailed, reason).
Expected<PairInspection> InspectPair(const Scan& parent, const Scan& child, const RegisterOptions& options,
                                     const InspectOptions& inspect, ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::pipeline
