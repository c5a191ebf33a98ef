#include "core/pipeline/register_options.h"

#include "core/pipeline/scale_defaults.h"

namespace scanreg::pipeline {

const char* FineMethodName(FineMethod method) {
  switch (method) {
    case FineMethod::kKeypoints: return "keypoints";
    case FineMethod::kDense: return "dense";
    case FineMethod::kEm: return "em";
    case FineMethod::kProjectiveIcp: return "projective-icp";
  }
  return "?";
}
const char* CoarseMethodName(CoarseMethod method) { return method == CoarseMethod::kEpnp ? "epnp" : "3d"; }

const char* FeatureSourcesName(FeatureSources sources) {
  switch (sources) {
    case FeatureSources::kSift: return "sift";
    case FeatureSources::kGeometric: return "fpfh";
    case FeatureSources::kBoth: return "both";
  }
  return "?";
}

const std::vector<FeatureSources>& AllFeatureSources() {
  static const std::vector<FeatureSources> all = {FeatureSources::kBoth, FeatureSources::kSift,
                                                  FeatureSources::kGeometric};
  return all;
}

const std::vector<FineMethod>& AllFineMethods() {
  static const std::vector<FineMethod> all = {FineMethod::kDense, FineMethod::kKeypoints, FineMethod::kEm,
                                              FineMethod::kProjectiveIcp};
  return all;
}

const std::vector<CoarseMethod>& AllCoarseMethods() {
  static const std::vector<CoarseMethod> all = {CoarseMethod::k3d, CoarseMethod::kEpnp};
  return all;
}

Status LinkThresholds::Validate() const {
  if (weak_inliers < 3 || !(min_overlap >= 0 && min_overlap <= weak_overlap &&
                                                         weak_overlap <= 1) ||
      !(weak_rms_m > 0 && weak_rms_m <= max_rms_m) || !(weak_conflict >= 0 && weak_conflict <= max_conflict) ||
      !(plan_view_conflict >= 0 && plan_view_conflict <= weak_conflict)) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "link thresholds: need weak_inliers >= 3, 0 <= min_overlap <= weak_overlap <= 1, "
                     "0 < weak_rms <= max_rms and 0 <= plan_view_conflict <= weak_conflict <= max_conflict");
  }
  return Status::Ok();
}

RegisterOptions::RegisterOptions() {
  coarse.inlier_threshold_m = 0;
  coarse.ambiguity_distance_m = 0;
  dense_icp.voxel_m = 0;
  dense_icp.max_correspondence_schedule_m.clear();
  dense_icp.robust_scale_floor_m = 0;
  keypoint_icp.max_correspondence_m = 0;
  reliability.max_range_std_m = 0;
}

Status RegisterOptions::Validate() const {
  if (global_partners < 0)
    return MakeError(ErrorCode::kInvalidArgument, "global partners must be >= 0 (0: every overlapping pair)");
  if (candidates < 0)
    return MakeError(ErrorCode::kInvalidArgument, "candidate partners per scan must be 0 (every pair) or more");
  if (Status s = spheres.Validate(); !s) return s;
  if (checkers.size_m != 0)
    if (Status s = checkers.Validate(); !s) return s;
  if (Status s = georef.Validate(); !s) return s;
  if (!(range_sigma_m >= 0 && range_sigma_m < 1)) {
    return MakeError(ErrorCode::kInvalidArgument, "range sigma must be between 0 and 1 m (0: from the data)");
  }
  if (!(overlap_distance_m == 0 || (overlap_distance_m >= 1e-5 && overlap_distance_m <= 100))) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "the overlap distance must be between 0.00001 and 100 m (0: from the data); below that it is "
                     "finer than any scanner measures");
  }
  // Unset lengths checked at nominal values (they are resolved from the data when registering).
  const RegisterOptions o = WithLengths(*this, 0.012, overlap_distance_m > 0 ? overlap_distance_m : 0.1);
  for (Status s : {o.sift.Validate(), o.match.Validate(), o.reliability.Validate(), o.coarse.Validate(),
                   o.keypoint_icp.Validate(), o.dense_icp.Validate(), o.thresholds.Validate()}) {
    if (!s) return s;
  }
  if (UsesGeometric(features)) {
    if (Status s = geometric.Validate(); !s) return s;
  }
  return Status::Ok();
}

}  // namespace scanreg::pipeline
