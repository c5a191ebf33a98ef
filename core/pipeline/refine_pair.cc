#include "core/pipeline/refine_pair.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/pipeline/fine_align.h"
#include "core/pipeline/scale_defaults.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string Format(const char* fmt, double a, double b) {
  char buf[400];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

// The link's surface evidence at its pose.
void SetEvidence(const AlignmentEvidence& e, io::LinkRecord& link) {
  link.overlap = e.overlap;
  link.rms_m = e.rms_m;
  link.conflict = e.conflict;
  link.moving = e.moving;
}

// Fails or weakens the link when its surfaces say so; true when they did.
bool JudgeSurfaces(const LinkThresholds& t, io::LinkRecord& link) {
  std::string reason;
  if (!(reason = SurfaceFailure(t, link)).empty()) {
    link.status = io::LinkStatus::kFailed;
  } else if (!(reason = SurfaceWeakness(t, link)).empty()) {
    link.status = io::LinkStatus::kWeak;
  } else {
    return false;
  }
  link.reason = reason;
  return true;
}

}  // namespace

RegisterOptions ScaledToReach(RegisterOptions o) {
  const double d = o.overlap_distance_m;
  o.dense_icp.voxel_m = std::min(o.dense_icp.voxel_m, 0.5 * d);
  o.dense_icp.max_correspondence_schedule_m = {d, 0.5 * d, 0.25 * d};
  return o;
}

io::LinkRecord RefinePair(const PreparedScan& parent, const PreparedScan& child, const Eigen::Isometry3d& initial,
                          const RegisterOptions& options, double evidence_m, const CancelToken& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  io::LinkRecord link;
  link.parent = parent.name;
  link.child = child.name;
  link.method = std::string("none+") + FineMethodName(options.fine);
  link.parent_from_child = initial;
  // EM from far (the reach several times the evidence distance) stalls on a wrong pose where
  // dense ICP does not (the bunny from 5 deg / 5 mm: one loop 2 deg open): dense ICP first, then
  // the EM from there within 4 evidence distances.
  Eigen::Isometry3d start = initial;
  RegisterOptions fine_options = options;
  if (options.fine != FineMethod::kDense && options.overlap_distance_m > 4 * evidence_m) {
    RegisterOptions icp = options;
    icp.fine = FineMethod::kDense;
    if (Expected<FineResult> pre = AlignFine(parent, child, initial, icp, cancel); pre && pre->iterations > 0) {
      start = pre->parent_from_child;
      fine_options.overlap_distance_m = 4 * evidence_m;
    }
  }
  Expected<FineResult> fine = AlignFine(parent, child, start, fine_options, cancel);
  if (!fine) {
    link.status = io::LinkStatus::kFailed;
    link.reason = fine.error().message;
  } else {
    link.parent_from_child = fine->parent_from_child;
    link.iterations = fine->iterations;
    // The start poses are meant to be close: a refinement that walks far away has diverged (measured
    // on the bunny: EM on a 38 % overlap pair 135 deg apart ended 45 deg off).
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3f& p : child.samples) centre += p.cast<double>();
    centre /= std::max<double>(1.0, child.samples.size());
    const double moved = (link.parent_from_child * centre - initial * centre).norm();
    const AlignmentEvidence e = EvaluateAlignment(parent, child, link.parent_from_child, evidence_m);
    SetEvidence(e, link);
    const LinkThresholds& t = options.thresholds;
    link.status = io::LinkStatus::kOk;
    if (!e.unavailable.empty()) {
      link.status = io::LinkStatus::kFailed;
      link.reason = e.unavailable;
    } else if (fine->iterations == 0) {  // not one step: the pose is the start pose, with no evidence of ours
      link.status = io::LinkStatus::kFailed;
      link.reason = Format(
          "the fine step could not start: too few correspondences within the overlap distance %.1f mm at "
          "samples of %.1f mm; they may be too large for this scan's size (set the range noise and the overlap "
          "distance for this data)",
          1e3 * options.overlap_distance_m, 1e3 * options.dense_icp.voxel_m);
    } else if (moved > 2 * options.overlap_distance_m) {
      link.status = io::LinkStatus::kFailed;
      link.reason = Format(
          "the refinement moved the scan %.1f mm from its current pose (more than twice the overlap "
          "distance %.1f mm): diverged; correct the start pose or raise the overlap distance",
          1e3 * moved, 1e3 * options.overlap_distance_m);
    } else if (!JudgeSurfaces(t, link) && !fine->converged) {
      link.status = io::LinkStatus::kWeak;
      link.reason = "the fine step stopped at its iteration cap before converging";
    }
    // Never worse than the start (issue 33): a refinement that ends weak or failed, fitting worse
    // than its start (a higher RMS over the overlap, and no fewer points in free space), keeps the
    // start, judged on its own evidence (measured on an office floor: a room station seen through
    // a door, refined from its registered pose, slid 2.2 deg and 75 mm to double its overlap, RMS
    // 10.4 -> 24.5 mm).
    if (link.status != io::LinkStatus::kOk && e.unavailable.empty() && fine->iterations > 0) {
      const AlignmentEvidence e0 = EvaluateAlignment(parent, child, initial, evidence_m);
      if (e0.unavailable.empty() && e0.overlap > 0 && e0.rms_m < e.rms_m &&
          !FreeSpaceRefutes(e.ViolationRate(), e0.ViolationRate())) {
        link.parent_from_child = initial;
        SetEvidence(e0, link);
        link.method += Format(" (start kept: refined, RMS %.1f mm)", 1e3 * e.rms_m, 0.0);
        link.status = io::LinkStatus::kOk;
        link.reason.clear();
        JudgeSurfaces(t, link);
      }
    }
  }
  if (cancel.IsCancelled()) {
    link.status = io::LinkStatus::kFailed;
    link.reason = "cancelled";
  }
  link.seconds = Since(t0);
  return link;
}


Expected<io::LinkRecord> RefinePairFromPose(const Scan& parent, const Scan& child, const Eigen::Isometry3d& initial,
                                            const RegisterOptions& raw_options, double reach_m,
                                            const CancelToken& cancel) {
  if (Status s = raw_options.Validate(); !s) return s.error();
  if (raw_options.fine == FineMethod::kKeypoints) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "refining from a pose has no feature matches for the fine method keypoints; use em, "
                     "projective-icp or dense");
  }
  if (!(reach_m >= 0) || !std::isfinite(reach_m)) {
    return MakeError(ErrorCode::kInvalidArgument, "the refinement's reach must be a distance of 0 or more");
  }
  ProjectScale scale;
  Expected<RegisterOptions> resolved = ResolveLengths(raw_options, {&parent, &child}, &scale);
  if (!resolved) return resolved.error();
  const double evidence_m = resolved->overlap_distance_m;
  if (reach_m == 0) {  // as far as the two poses are apart (the scans' world_from_scan)
    reach_m = StartDistance({&parent, &child}, evidence_m, scale.extent_m > 0 ? scale.extent_m : 100 * evidence_m);
  }
  resolved->overlap_distance_m = std::max(reach_m, evidence_m);
  const RegisterOptions options = ScaledToReach(*resolved);
  PreparedScan prepared[2];
  const Scan* scans[2] = {&parent, &child};
  for (int k = 0; k < 2; ++k) {
    std::vector<Eigen::Vector3d> pts;
    for (std::size_t i = 0; i < scans[k]->size(); ++i)
      if (scans[k]->valid[i]) pts.push_back(scans[k]->points[i].cast<double>());
    if (pts.empty())
      return MakeError(ErrorCode::kInvalidArgument, "scan '" + scans[k]->name + "' has no valid point; remove it");
    HoldScan(*scans[k], &prepared[k]);
    prepared[k].samples = ToFloat(VoxelDownsample(pts, options.dense_icp.voxel_m));
    prepared[k].surface_options = options.dense_icp;
    PrepareRays(*scans[k], evidence_m, &prepared[k]);
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "refinement cancelled");
  return RefinePair(prepared[0], prepared[1], initial, options, evidence_m, cancel);
}

}  // namespace scanreg::pipeline
