#include "core/pipeline/refine_project.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include "core/common/log.h"
#include "core/pipeline/refine_pair.h"
#include "core/pipeline/register_pair.h"
#include "core/pipeline/registration_driver.h"
#include "core/pipeline/scale_defaults.h"
#include "core/pipeline/verify_poses.h"
#include "core/registration/point_index.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

std::string Format(const char* fmt, double a, double b) {
  char buf[400];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

Expected<ProjectRegistration> RegisterFromCurrentPoses(const std::vector<Scan>& scans, const UserChoices& user,
                                                       const RegisterOptions& raw_options, ProgressSink& progress,
                                                       const CancelToken& cancel) {
  if (Status s = raw_options.Validate(); !s) return s.error();
  if (raw_options.fine == FineMethod::kKeypoints) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "coarse method none (refine from the current poses) has no feature matches for the fine method "
                     "keypoints; use em, projective-icp or dense");
  }
  const int n = static_cast<int>(scans.size());
  if (n < 2) return MakeError(ErrorCode::kInvalidArgument, "registration needs at least two scans");
  std::vector<const Scan*> all;
  for (const Scan& s : scans) all.push_back(&s);
  ProjectScale scale;
  Expected<RegisterOptions> resolved = ResolveLengths(raw_options, all, &scale);
  if (!resolved) return resolved.error();
  const double evidence_m = resolved->overlap_distance_m;
  if (raw_options.overlap_distance_m == 0) {
    // The fine step starts from the current poses: its reach, and the overlap that links scans,
    // follow how far apart they are (the RMS thresholds stay at the data's scale).
    resolved->overlap_distance_m = StartDistance(all, resolved->overlap_distance_m, scale.extent_m);
    char buf[160];
    std::snprintf(buf, sizeof buf, "refining from the current poses: overlap distance %.3g m (how far apart they are)",
                  resolved->overlap_distance_m);
    LogInfo(buf);
  }
  const RegisterOptions options = ScaledToReach(*resolved);
  const auto t_start = std::chrono::steady_clock::now();
  ProjectRegistration result;

  // Voxel samples of every scan, their indices, and the directed overlap at the current poses.
  std::vector<PreparedScan> prepared(n);
  std::vector<std::unique_ptr<PointIndex>> index(n);
  for (int i = 0; i < n; ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t k = 0; k < scans[i].size(); ++k)
      if (scans[i].valid[k]) pts.push_back(scans[i].points[k].cast<double>());
    if (pts.empty())
      return MakeError(ErrorCode::kInvalidArgument, "scan '" + scans[i].name + "' has no valid point; remove it");
    HoldScan(scans[i], &prepared[i]);
    prepared[i].samples = ToFloat(VoxelDownsample(pts, options.dense_icp.voxel_m));
    prepared[i].surface_options = options.dense_icp;
    PrepareRays(scans[i], evidence_m, &prepared[i]);
    index[i] = std::make_unique<PointIndex>(ToDouble(prepared[i].samples));
  }
  result.seconds_features = Since(t_start);
  const auto t_overlap = std::chrono::steady_clock::now();
  Eigen::MatrixXd overlap = Eigen::MatrixXd::Zero(n, n);
  result.confusion = Eigen::MatrixXi::Zero(n, n);  // overlap in per mille: the scan order's edge weights
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      if (i == j) continue;
      const Eigen::Isometry3d rel = scans[i].world_from_scan.inverse() * scans[j].world_from_scan;
      overlap(i, j) = SampleOverlap(*index[i], prepared[j].samples, rel, options.overlap_distance_m);
      result.confusion(i, j) = static_cast<int>(std::lround(1000 * overlap(i, j)));
    }
  result.seconds_matching = Since(t_overlap);

  Expected<ScanOrderChoices> choices = ResolveScanOrderChoices(scans, user, options.root);
  if (!choices) return choices.error();
  LinkSource source;
  source.weights = result.confusion;
  source.min_weight = std::max(1, static_cast<int>(std::lround(1000 * options.thresholds.min_overlap)));
  source.register_pair = [&](int parent, int child) {
    const Eigen::Isometry3d initial = scans[parent].world_from_scan.inverse() * scans[child].world_from_scan;
    PairResult r;
    r.link = RefinePair(prepared[parent], prepared[child], initial, options, evidence_m, cancel);
    return r;
  };
  source.verb = "refining";
  source.loop_checks = true;  // a link whose loop does not close is failed, never chained (issue 11)
  source.min_check_weight = source.min_weight;
  source.overlap = overlap;
  source.extra_overlap = options.thresholds.weak_overlap;
  source.has_coarse = false;
  source.no_link_reason = Format("no scan overlaps it by %.0f %% within %.3f m at the current poses",
                                 100 * options.thresholds.min_overlap, options.overlap_distance_m);
  SubProgress pair_progress(progress, 0.05, 0.95);
  if (Status s = DriveRegistration(scans, *choices, source, options, pair_progress, cancel, &result); !s) {
    return s.error();
  }
  // Registered means verified: the multi-view step, and every pose against its start (issue 33).
  // Samples at half the data's overlap distance: fine enough that a sample's nearest neighbour on the
  // other surface lies on its tangent plane (the refinement's samples follow the reach, maybe coarse).
  std::vector<std::vector<Eigen::Vector3d>> samples(n);
  for (int i = 0; i < n; ++i) {
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t k = 0; k < scans[i].size(); ++k)
      if (scans[i].valid[k]) pts.push_back(scans[i].points[k].cast<double>());
    samples[i] = VoxelDownsample(pts, 0.5 * evidence_m);
  }
  VerifyOptions verify;
  verify.cutoff_m = evidence_m;
  verify.evidence_m = evidence_m;
  verify.noise_m = options.range_sigma_m;
  verify.min_overlap = options.thresholds.min_overlap;
  verify.multiview = options.multiview;
  SubProgress verify_progress(progress, 0.95, 1.0);
  if (Status s = VerifyAgainstStart(scans, samples, *choices, verify, verify_progress, cancel, &result); !s) {
    return s.error();
  }
  result.seconds_total = Since(t_start);
  progress.Report(1.0, "registration done");
  return result;
}

}  // namespace scanreg::pipeline
