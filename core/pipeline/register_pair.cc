#include "core/pipeline/register_pair.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "core/geometry/transform.h"
#include "core/pipeline/fine_align.h"
#include "core/registration/consistency.h"
#include "core/registration/point_index.h"
#include "core/registration/surface_distance.h"
#include "core/registration/visibility.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

std::vector<Eigen::Vector3d> ValidPoints(const Scan& scan) {
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) pts.push_back(scan.points[i].cast<double>());
  return pts;
}

std::string Format(const char* fmt, double a, double b = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

// Fills link.status and link.reason from the evidence and the thresholds.
void Classify(const LinkThresholds& t, io::LinkRecord& link) {
  std::string reason;
  if (link.consistent < t.min_inliers) {
    link.status = io::LinkStatus::kFailed;
    link.reason = "only " + std::to_string(link.consistent) + " consistent correspondences (minimum " +
                  std::to_string(t.min_inliers) + ")";
  } else if (!(reason = SurfaceFailure(t, link)).empty()) {
    link.status = io::LinkStatus::kFailed;
    link.reason = reason;
  } else if (link.consistent < t.weak_inliers) {
    link.status = io::LinkStatus::kWeak;
    link.reason = "few consistent correspondences (" + std::to_string(link.consistent) + ")";
  } else if (!(reason = SurfaceWeakness(t, link)).empty()) {
    link.status = io::LinkStatus::kWeak;
    link.reason = reason;
  } else {
    link.status = io::LinkStatus::kOk;
    link.reason.clear();
  }
}

}  // namespace

std::string SurfaceFailure(const LinkThresholds& t, const io::LinkRecord& link) {
  if (link.overlap < t.min_overlap) {
    return Format("overlap %.1f %% is below the minimum %.1f %%: the scans do not share a surface", 100 * link.overlap,
                  100 * t.min_overlap);
  }
  if (link.conflict > t.max_conflict) {
    return Format("%.1f %% of the points lie in the other scanner's free space (maximum %.1f %%): wrong pose",
                  100 * link.conflict, 100 * t.max_conflict);
  }
  if (link.rms_m > t.max_rms_m) {
    return Format("RMS %.1f mm over the overlap exceeds %.1f mm", 1000 * link.rms_m, 1000 * t.max_rms_m);
  }
  return "";
}

std::string SurfaceWeakness(const LinkThresholds& t, const io::LinkRecord& link) {
  if (link.overlap < t.weak_overlap) return Format("small overlap (%.1f %%)", 100 * link.overlap);
  if (link.conflict > t.weak_conflict) {
    return Format("%.1f %% of the points conflict with the other scan's free space", 100 * link.conflict);
  }
  if (link.rms_m > t.weak_rms_m) return Format("RMS %.1f mm over the overlap is high", 1000 * link.rms_m);
  return "";
}

void PrepareScan(const Scan& scan, const RegisterOptions& options, PreparedScan* prepared) {
  prepared->scan = &scan;
  prepared->confidence = ConfidenceMap(scan, options.reliability);
  prepared->samples = VoxelDownsample(ValidPoints(scan), options.dense_icp.voxel_m);
}

AlignmentEvidence EvaluateAlignment(const PreparedScan& parent, const PreparedScan& child,
                                    const Eigen::Isometry3d& parent_from_child, double max_distance_m) {
  AlignmentEvidence e;
  const std::vector<Eigen::Vector3d>& parent_pts = parent.samples;
  const std::vector<Eigen::Vector3d> child_pts = ThinEvenly(child.samples, 8000);
  if (parent_pts.size() < 8 || child_pts.empty()) return e;
  std::vector<Eigen::Vector3d> queries;
  queries.reserve(child_pts.size());
  for (const Eigen::Vector3d& c : child_pts) queries.push_back(parent_from_child * c);
  const std::vector<double> d = PointToSurfaceDistances(PointIndex(parent_pts), parent_pts, queries, max_distance_m);
  double sum_sq = 0.0;
  long overlapping = 0;
  for (double di : d) {
    if (di < 0) continue;
    sum_sq += di * di;
    ++overlapping;
  }
  e.overlap = double(overlapping) / double(child_pts.size());
  e.rms_m = overlapping ? std::sqrt(sum_sq / double(overlapping)) : 0.0;
  const double margin = std::max(0.2, 2 * max_distance_m);
  e.conflict = std::max(FreeSpaceViolations(*parent.scan, *child.scan, parent_from_child, margin).fraction(),
                        FreeSpaceViolations(*child.scan, *parent.scan, parent_from_child.inverse(), margin).fraction());
  return e;
}

namespace {

// Angular spacing of the grid (radians): the larger of the column and row steps; 0 when unknown.
double AngularStep(const Scan& scan) {
  if (scan.angles.empty() || scan.cols < 2 || scan.rows < 2) return 0.0;
  const double az = std::abs(scan.angles.azimuth.back() - scan.angles.azimuth.front()) / (scan.cols - 1);
  const double el = std::abs(scan.angles.elevation.back() - scan.angles.elevation.front()) / (scan.rows - 1);
  return std::max(az, el);
}

bool Distinct(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const CoarseOptions& o) {
  return (a.translation() - b.translation()).norm() > o.ambiguity_distance_m ||
         RotationAngle(a.linear().transpose() * b.linear()) > o.ambiguity_angle_rad;
}

struct Hypothesis {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  AlignmentEvidence evidence;
  int iterations = 0;
};

// Overlap, discounted by free-space conflicts: a pose that puts points where the other scanner
// saw through is wrong however well the walls overlap.
double Score(const Hypothesis& h) { return h.evidence.overlap * std::max(0.0, 1.0 - 10.0 * h.evidence.conflict); }

// Fine registration from one coarse pose, then the shared evidence.
Hypothesis Refine(const PreparedScan& parent, const PreparedScan& child, const std::vector<Correspondence3d>& corr,
                  const Eigen::Isometry3d& coarse, double keypoint_threshold, double angular,
                  const RegisterOptions& options, const CancelToken& cancel) {
  Hypothesis h;
  h.parent_from_child = coarse;
  if (options.fine == FineMethod::kKeypoints) {
    std::vector<Eigen::Vector3d> pp, cp;
    for (int i : ConsistentIndices(corr, coarse, keypoint_threshold, angular)) {
      pp.push_back(corr[i].parent);
      cp.push_back(corr[i].child);
    }
    Expected<IcpResult> icp = KeypointIcp(pp, cp, coarse, options.keypoint_icp, cancel);
    if (icp) {
      h.parent_from_child = icp->parent_from_child;
      h.iterations = icp->iterations;
    }
  } else {
    // Dense ICP must converge to be trusted; EM's evidence below decides (it stops at its cap).
    Expected<FineResult> fine = AlignFine(parent, child, coarse, options, cancel);
    if (fine && (fine->converged || options.fine != FineMethod::kDense)) {
      h.parent_from_child = fine->parent_from_child;
      h.iterations = fine->iterations;
    }
  }
  h.evidence = EvaluateAlignment(parent, child, h.parent_from_child, options.overlap_distance_m);
  return h;
}

}  // namespace

PairResult RegisterPair(const PreparedScan& parent, const PreparedScan& child, const std::vector<FeatureMatch>& matches,
                        const RegisterOptions& options, const CancelToken& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  PairResult result;
  io::LinkRecord& link = result.link;
  link.parent = parent.scan->name;
  link.child = child.scan->name;
  link.method = std::string(CoarseMethodName(options.coarse.method)) + "+" + FineMethodName(options.fine);
  link.matches = static_cast<int>(matches.size());
  auto finish = [&]() -> PairResult {
    link.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return result;
  };
  auto fail = [&](const std::string& reason) {
    link.status = io::LinkStatus::kFailed;
    link.reason = cancel.IsCancelled() ? "cancelled" : reason;
    return finish();
  };

  // W §2 step 5: reliable 3D points of both keypoints of each match.
  std::vector<Correspondence3d> corr;
  corr.reserve(matches.size());
  std::vector<double> ranges;
  std::vector<int> match_of_corr;  // corr[k] comes from matches[match_of_corr[k]]
  for (const FeatureMatch& m : matches) {
    const Keypoint& kp = parent.features.keypoints[m.query];
    const Keypoint& kc = child.features.keypoints[m.train];
    const auto p = InterpolatePoint(*parent.scan, parent.confidence, kp.u, kp.v);
    const auto c = InterpolatePoint(*child.scan, child.confidence, kc.u, kc.v);
    if (!p || !c) continue;
    corr.push_back({p->cast<double>(), c->cast<double>()});
    ranges.push_back(c->norm());
    match_of_corr.push_back(static_cast<int>(&m - matches.data()));
  }
  link.reliable = static_cast<int>(corr.size());
  if (corr.empty()) return fail("no reliable correspondence: the scans share no matched features");

  // Keypoint localisation error grows with range: about two grid steps of angle (ours; W uses
  // fixed thresholds, which at 15 m and 0.24° would reject most true pairs).
  const double angular = 2.0 * std::max(AngularStep(*parent.scan), AngularStep(*child.scan));
  std::nth_element(ranges.begin(), ranges.begin() + ranges.size() / 2, ranges.end());
  CoarseOptions coarse_options = options.coarse;
  coarse_options.inlier_threshold_m = std::max(coarse_options.inlier_threshold_m, angular * ranges[ranges.size() / 2]);

  // W §2 step 7: coarse registration.
  Expected<CoarseResult> coarse = EstimateCoarse(corr, coarse_options, cancel);
  if (!coarse) return fail("coarse registration failed: " + coarse.error().message);
  link.ransac_inliers = coarse->inliers;
  link.iterations = coarse->iterations;
  result.coarse_parent_from_child = coarse->parent_from_child;
  result.coarse_ok = !coarse->ambiguous;
  for (int k : coarse->inlier_indices) result.coarse_inlier_matches.push_back(match_of_corr[k]);

  // Fine registration of the best hypothesis and of its distinct competitor (repeated façades):
  // the surfaces, not the feature counts, decide between them (beyond W).
  const double threshold = ConsistencyThreshold(options.range_sigma_m);
  std::vector<Hypothesis> hyps;
  hyps.push_back(Refine(parent, child, corr, coarse->parent_from_child, threshold, angular, options, cancel));
  if (coarse->competitor && coarse->competitor_support >= 3) {
    // Screen the competitor with a short dense ICP first: most competitors end far below the best.
    RegisterOptions screen = options;
    screen.dense_icp.max_correspondence_schedule_m = {options.dense_icp.max_correspondence_schedule_m.front()};
    screen.dense_icp.max_iterations_per_stage = 10;
    Hypothesis h = Refine(parent, child, corr, *coarse->competitor, threshold, angular, screen, cancel);
    if (Score(h) >= 0.5 * options.coarse.ambiguity_ratio * Score(hyps.front())) {
      h = Refine(parent, child, corr, h.parent_from_child, threshold, angular, options, cancel);
    }
    hyps.push_back(h);
  }
  if (cancel.IsCancelled()) return fail("cancelled");
  std::sort(hyps.begin(), hyps.end(), [](const Hypothesis& a, const Hypothesis& b) { return Score(a) > Score(b); });
  const Hypothesis& best = hyps.front();
  link.parent_from_child = best.parent_from_child;
  link.iterations += best.iterations;
  link.overlap = best.evidence.overlap;
  link.rms_m = best.evidence.rms_m;
  link.conflict = best.evidence.conflict;
  link.consistent = static_cast<int>(ConsistentIndices(corr, best.parent_from_child, threshold, angular).size());
  // Ambiguous only when both poses fit well; when neither does, the evidence below fails the link.
  if (hyps.size() > 1 && Score(hyps[0]) >= options.thresholds.weak_overlap &&
      Distinct(hyps[0].parent_from_child, hyps[1].parent_from_child, options.coarse) &&
      Score(hyps[1]) >= options.coarse.ambiguity_ratio * Score(hyps[0])) {
    return fail(Format("ambiguous: two poses %.2f m apart fit the surfaces almost equally (score %.2f vs ",
                       (hyps[0].parent_from_child.translation() - hyps[1].parent_from_child.translation()).norm(),
                       Score(hyps[0])) +
                Format("%.2f: overlap discounted by free-space conflicts); repeated structure — set the parent by hand",
                       Score(hyps[1])));
  }
  Classify(options.thresholds, link);
  if (link.status == io::LinkStatus::kOk && coarse->ambiguous) {
    link.status = io::LinkStatus::kWeak;
    link.reason = "features were ambiguous (" + coarse->reason + "); the surfaces decided";
  }
  return finish();
}

}  // namespace scanreg::pipeline
