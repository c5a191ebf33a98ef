#include "core/pipeline/register_pair.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

#include "core/geometry/transform.h"
#include "core/pipeline/fine_align.h"
#include "core/pipeline/scan_store.h"
#include "core/registration/reliable_points.h"
#include "core/registration/consistency.h"
#include "core/registration/plan_view.h"
#include "core/registration/point_index.h"
#include "core/registration/surface_distance.h"
#include "core/registration/visibility.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {
namespace {

std::string Format(const char* fmt, double a, double b = 0.0) {
  char buf[400];
  std::snprintf(buf, sizeof buf, fmt, a, b);
  return buf;
}

// Fills link.status and link.reason from the evidence and the thresholds.
// required: the support a pose needs (the coarse step's chance model).
void Classify(const LinkThresholds& t, int required, io::LinkRecord& link) {
  std::string reason;
  if (link.consistent < required) {
    link.status = io::LinkStatus::kFailed;
    link.reason = "only " + std::to_string(link.consistent) + " consistent correspondences (minimum " +
                  std::to_string(required) + ")";
  } else if (!(reason = SurfaceFailure(t, link)).empty()) {
    link.status = io::LinkStatus::kFailed;
    link.reason = reason;
  } else if (link.consistent < std::max(required, t.weak_inliers)) {
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

namespace {

// Angular spacing of the grid (radians): the larger of the column and row steps; 0 when unknown.
double AngularStep(const Scan& scan) {
  if (scan.angles.empty() || scan.cols < 2 || scan.rows < 2) return 0.0;
  const double az = std::abs(scan.angles.azimuth.back() - scan.angles.azimuth.front()) / (scan.cols - 1);
  const double el = std::abs(scan.angles.elevation.back() - scan.angles.elevation.front()) / (scan.rows - 1);
  return std::max(az, el);
}

// Columns cover (nearly) the whole circle: at least 33 of 36 ten-degree sectors.
bool FullCircle(const AngularGrid& angles) {
  std::array<bool, 36> seen{};
  for (float a : angles.azimuth) {
    if (!std::isfinite(a)) continue;
    const int k = static_cast<int>(std::floor((a + M_PI) / (2.0 * M_PI) * 36.0));
    seen[std::clamp(k, 0, 35)] = true;
  }
  return std::count(seen.begin(), seen.end(), true) >= 33;
}

// Whether this pose puts two tripod stations (full panoramas whose grids came with their files) on
// one spot: nearer than `fraction` of the nearer one's median range. Measured on office floors:
// poses put stations on their twins' spots 0.03-0.17 of it away; neighbouring street stations 3 m
// apart are 0.19 of it. Mobile lidar (KITTI sweeps 0.7 m apart: 0.05) comes as point lists, whose
// grids are organized here, and is not asked.
bool SameSpot(const PreparedScan& parent, const PreparedScan& child, const Eigen::Isometry3d& parent_from_child,
              double fraction) {
  if (!parent.panoramic || !child.panoramic) return false;
  return parent_from_child.translation().norm() < fraction * std::min(parent.median_range_m, child.median_range_m);
}

}  // namespace

Expected<std::shared_ptr<const Scan>> PreparedScan::Full() const {
  if (scan) return std::shared_ptr<const Scan>(std::shared_ptr<const Scan>(), scan);
  if (!store) return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "' is not available");
  Expected<std::shared_ptr<const Scan>> full = store->Get(index);
  if (!full) return MakeError(full.error().code, "scan '" + name + "' could not be read again: " + full.error().message);
  return full;
}

std::shared_ptr<const IcpSurface> PreparedScan::Surface() const {
  if (samples.empty()) return nullptr;
  const auto build = [this] { return std::make_shared<const IcpSurface>(ToDouble(samples), surface_options); };
  if (store) return store->Surface(index, build);
  if (!memo) return build();
  std::call_once(memo->once, [&] { memo->surface = build(); });
  return memo->surface;
}

void HoldScan(const Scan& scan, PreparedScan* prepared) {
  prepared->name = scan.name;
  prepared->scan = &scan;
  prepared->angular_step = AngularStep(scan);
  prepared->memo = std::make_shared<PreparedScan::SurfaceMemo>();
}

void PrepareRays(const Scan& scan, double evidence_m, PreparedScan* prepared) {
  prepared->rays.reset();
  if (scan.HasSensor() && !HasViewpoint(scan)) prepared->rays = std::make_shared<const RayFreeSpace>(scan, evidence_m);
}

void PrepareScan(const Scan& scan, const RegisterOptions& options, PreparedScan* prepared) {
  HoldScan(scan, prepared);
  const std::vector<std::uint8_t> confidence = ConfidenceMap(scan, options.reliability);
  prepared->keypoint_points.clear();
  prepared->keypoint_points.reserve(prepared->features.keypoints.size());
  for (const Keypoint& k : prepared->features.keypoints) {
    const std::optional<Eigen::Vector3f> p = InterpolatePoint(scan, confidence, k.u, k.v);
    prepared->keypoint_points.push_back(p ? *p : Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  }
  prepared->samples = ToFloat(VoxelDownsample(ValidPoints(scan), options.dense_icp.voxel_m));
  prepared->surface_options = options.dense_icp;
  prepared->plan = MakePlanView(prepared->geometric, scan);
  prepared->panoramic = scan.grid_from_file && FullCircle(scan.angles);
  PrepareRays(scan, options.overlap_distance_m, prepared);
  std::vector<float> ranges;
  ranges.reserve(prepared->samples.size());
  for (const Eigen::Vector3f& p : prepared->samples) ranges.push_back(p.norm());
  if (!ranges.empty()) {
    std::nth_element(ranges.begin(), ranges.begin() + ranges.size() / 2, ranges.end());
    prepared->median_range_m = ranges[ranges.size() / 2];
  }
}

int GeometricWeight(const PreparedScan& parent, const PreparedScan& child, const std::vector<GeometricMatch>& geometric,
                    const RegisterOptions& options) {
  int weight = 0;
  const bool levelled = parent.geometric.levelled && child.geometric.levelled;
  if (geometric.size() >= 8) {
    const Eigen::Isometry3d lp = parent.geometric.Levelling(), lc = child.geometric.Levelling();
    std::vector<Correspondence3d> corr;
    for (const GeometricMatch& g : geometric)
      corr.push_back({lp * parent.geometric.points[g.parent], lc * child.geometric.points[g.child],
                      1.5 * parent.geometric.VoxelOf(g.parent)});
    CoarseOptions o = options.coarse;
    o.method = CoarseMethod::k3d;
    o.levelled = levelled;
    o.max_iterations = 2000;
    o.inlier_threshold_m = 1.5 * parent.geometric.voxel_m;
    CancelToken never;
    if (Expected<CoarseResult> c = EstimateCoarse(corr, o, never); c.ok()) weight += c->inliers;
  }
  if (parent.plan.usable && child.plan.usable) {
    const std::vector<PlanHypothesis> h = PlanHypotheses(parent.plan, child.plan);
    // Unrelated street scans still correlate at about 0.4-0.5 (measured: 10 and 15 m spacing,
    // neighbours 0.66-0.83, others 0.37-0.62); every levelled pair stays a candidate (weight >= 1).
    if (!h.empty()) weight += std::max(1, static_cast<int>(std::lround(100.0 * (h.front().score - 0.5))));
  }
  return weight;
}

AlignmentEvidence EvaluateAlignment(const PreparedScan& parent, const PreparedScan& child,
                                    const Eigen::Isometry3d& parent_from_child, double max_distance_m) {
  AlignmentEvidence e;
  const std::vector<Eigen::Vector3d> child_pts = ThinEvenly(child.samples, 8000);
  if (parent.samples.size() < 8 || child_pts.empty()) return e;
  std::vector<Eigen::Vector3d> queries;
  queries.reserve(child_pts.size());
  for (const Eigen::Vector3d& c : child_pts) queries.push_back(parent_from_child * c);
  const std::shared_ptr<const IcpSurface> surface = parent.Surface();  // its points: the parent's samples
  const std::vector<double> d = PointToSurfaceDistances(*surface->index, surface->points, queries, max_distance_m);
  double sum_sq = 0.0;
  long overlapping = 0;
  for (double di : d) {
    if (di < 0) continue;
    sum_sq += di * di;
    ++overlapping;
  }
  e.overlap = double(overlapping) / double(child_pts.size());
  e.rms_m = overlapping ? std::sqrt(sum_sq / double(overlapping)) : 0.0;
  FreeSpaceOptions free_space;
  free_space.margin_m = 2 * max_distance_m;
  const Expected<std::shared_ptr<const Scan>> a = parent.Full(), b = child.Full();
  if (!a || !b) {
    e.unavailable = (a ? b : a).error().message;
    return e;
  }
  const PairFreeSpace f = PairFreeSpaceCheck(**a, **b, parent_from_child, free_space, parent.rays.get(), child.rays.get());
  e.conflict = f.conflict();
  e.moving = f.moving();
  e.violations = f.a_sees_b.violations + f.b_sees_a.violations;
  e.tested = f.a_sees_b.tested + f.b_sees_a.tested;
  return e;
}

bool FreeSpaceRefutes(double rate_kept, double rate_other) {
  return rate_other >= 3.0 * rate_kept && rate_other - rate_kept >= kClearViolationRate;
}

namespace {

bool Distinct(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const CoarseOptions& o) {
  return (a.translation() - b.translation()).norm() > o.ambiguity_distance_m ||
         RotationAngle(a.linear().transpose() * b.linear()) > o.ambiguity_angle_rad;
}

struct Hypothesis {
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();
  AlignmentEvidence evidence;
  int iterations = 0;
  bool screened_only = false;  // from the short screening ICP alone
};

// Overlap, discounted by free-space conflicts: a pose that puts points where the other scanner
// saw through is wrong however well the walls overlap. Conflicts on object-sized clusters (traffic
// at the true pose, or posts and cars of a pose shifted along identical façades) discount less.
double Score(const Hypothesis& h) {
  return h.evidence.overlap * std::max(0.0, 1.0 - 10.0 * h.evidence.conflict) * (1.0 - h.evidence.moving);
}

// A pose that fits the surfaces as a link needs to at least: no surface failure, enough overlap.
bool Fits(const LinkThresholds& t, const Hypothesis& h) {
  io::LinkRecord l;
  l.overlap = h.evidence.overlap;
  l.rms_m = h.evidence.rms_m;
  l.conflict = h.evidence.conflict;
  return SurfaceFailure(t, l).empty() && l.overlap >= t.weak_overlap;
}

bool FreerThan(const Hypothesis& a, const Hypothesis& b) {
  return FreeSpaceRefutes(a.evidence.ViolationRate(), b.evidence.ViolationRate());
}

// Another distinct pose that fits the surfaces as a link would need to: enough overlap, a low RMS
// and no free-space conflict, static or object-sized. For a pose without feature support the
// overlap cannot rank two such poses: it favours the pose that puts the scanners nearer each other,
// whose dense near surfaces then cover each other (measured on an office floor, corridor stations
// 10.6 m apart: 47 % overlap for the corridor turned 180° about its middle, 21 % at the truth, both
// without conflict; issue 38). Null when there is none.
const Hypothesis* OtherFittingPose(const LinkThresholds& t, const Hypothesis& best, const std::vector<Hypothesis>& hyps,
                                   const std::vector<int>& rank, const CoarseOptions& coarse) {
  for (int k : rank) {
    const Hypothesis& h = hyps[k];
    if (&h == &best || !Distinct(best.parent_from_child, h.parent_from_child, coarse)) continue;
    io::LinkRecord l;
    l.overlap = h.evidence.overlap;
    l.rms_m = h.evidence.rms_m;
    l.conflict = h.evidence.conflict;
    if (SurfaceFailure(t, l).empty() && SurfaceWeakness(t, l).empty() && h.evidence.moving <= t.weak_conflict) return &h;
  }
  return nullptr;
}

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
                        const std::vector<GeometricMatch>& geometric, const RegisterOptions& options,
                        const CancelToken& cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  PairResult result;
  io::LinkRecord& link = result.link;
  link.parent = parent.name;
  link.child = child.name;
  link.method = std::string(CoarseMethodName(options.coarse.method)) + "+" + FineMethodName(options.fine);
  link.matches = static_cast<int>(matches.size());
  link.geometric_matches = static_cast<int>(geometric.size());
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
    const Eigen::Vector3f& p = parent.keypoint_points[m.query];
    const Eigen::Vector3f& c = child.keypoint_points[m.train];
    if (!p.allFinite() || !c.allFinite()) continue;
    corr.push_back({p.cast<double>(), c.cast<double>()});
    ranges.push_back(c.norm());
    match_of_corr.push_back(static_cast<int>(&m - matches.data()));
  }
  const int n_sift = static_cast<int>(corr.size());
  // FPFH samples are voxel centroids: they sit up to about a voxel (of their scale) from their partner.
  for (const GeometricMatch& g : geometric)
    corr.push_back({parent.geometric.points[g.parent], child.geometric.points[g.child],
                    1.5 * parent.geometric.VoxelOf(g.parent)});
  link.reliable = static_cast<int>(corr.size());
  const bool plan_views = parent.plan.usable && child.plan.usable;
  if (corr.empty() && !plan_views) return fail("no reliable correspondence: the scans share no matched features");

  // Keypoint localisation error grows with range: about two grid steps of angle (ours; W uses
  // fixed thresholds, which at 15 m and 0.24° would reject most true pairs).
  const double angular = 2.0 * std::max(parent.angular_step, child.angular_step);
  CoarseOptions coarse_options = options.coarse;
  if (!ranges.empty()) {
    std::nth_element(ranges.begin(), ranges.begin() + ranges.size() / 2, ranges.end());
    coarse_options.inlier_threshold_m = std::max(coarse_options.inlier_threshold_m, angular * ranges[ranges.size() / 2]);
  }

  // W §2 step 7: coarse registration, in levelled frames when both scans are levelled (issue 11,
  // item 3: heading + translation from 2 correspondences).
  const bool levelled = coarse_options.method == CoarseMethod::k3d && parent.geometric.levelled &&
                        child.geometric.levelled;
  const Eigen::Isometry3d level_parent = parent.geometric.Levelling();
  const Eigen::Isometry3d level_child = child.geometric.Levelling();
  const auto unlevel = [&](const Eigen::Isometry3d& t) { return level_parent.inverse() * t * level_child; };
  coarse_options.levelled = levelled;
  std::vector<Correspondence3d> levelled_corr = corr;
  if (levelled)
    for (Correspondence3d& c : levelled_corr) c = {level_parent * c.parent, level_child * c.child, c.tolerance_m};
  Expected<CoarseResult> coarse = EstimateCoarse(levelled_corr, coarse_options, cancel);
  if (!coarse && coarse.error().code == ErrorCode::kCancelled) return fail("cancelled");
  if (coarse) {
    if (levelled) {
      coarse->parent_from_child = unlevel(coarse->parent_from_child);
      if (coarse->competitor) coarse->competitor = unlevel(*coarse->competitor);
      link.method += " levelled";
    }
    link.ransac_inliers = coarse->inliers;
    link.iterations = coarse->iterations;
    result.coarse_parent_from_child = coarse->parent_from_child;
    result.coarse_ok = !coarse->ambiguous;
    for (int k : coarse->inlier_indices) {
      if (k < n_sift) {
        result.coarse_inlier_matches.push_back(match_of_corr[k]);
      } else {
        ++link.geometric_inliers;
      }
    }
  }
  // Plan-view poses (levelled scans, plan_view.h) when the correspondences do not settle the pose.
  std::vector<PlanHypothesis> plan;
  if (plan_views && (!coarse || coarse->ambiguous || coarse->inliers < options.thresholds.weak_inliers)) {
    plan = PlanHypotheses(parent.plan, child.plan);
  }
  if (!coarse && plan.empty()) return fail("coarse registration failed: " + coarse.error().message);

  // Consistent correspondences at a pose: SIFT within the range-noise threshold (W §2 step 8),
  // FPFH within their sampling threshold.
  const std::vector<Correspondence3d> sift_corr(corr.begin(), corr.begin() + n_sift);
  const std::vector<Correspondence3d> geometric_corr(corr.begin() + n_sift, corr.end());
  const double threshold = ConsistencyThreshold(options.range_sigma_m, 3.0, 0.3 * options.overlap_distance_m);

  // Fine registration of every start: the correspondences' best pose and its distinct competitor
  // (repeated façades), and the plan-view poses. The surfaces, not the feature counts, decide
  // between them (beyond W). All but the first are screened with a short dense ICP first.
  struct Start {
    Eigen::Isometry3d pose;
    bool from_plan;
  };
  std::vector<Start> starts;
  if (coarse) {
    starts.push_back({coarse->parent_from_child, false});
    if (coarse->competitor && coarse->competitor_support >= 3) starts.push_back({*coarse->competitor, false});
  }
  for (const PlanHypothesis& h : plan) starts.push_back({unlevel(h.parent_from_child), true});
  RegisterOptions screen = options;
  screen.dense_icp.max_correspondence_schedule_m = {options.dense_icp.max_correspondence_schedule_m.front()};
  screen.dense_icp.max_iterations_per_stage = 10;
  screen.dense_icp.max_samples = std::min(options.dense_icp.max_samples, 2000);
  std::vector<Hypothesis> hyps;
  std::vector<bool> hyp_from_plan;
  for (const Start& st : starts) {
    if (cancel.IsCancelled()) return fail("cancelled");
    Hypothesis h;
    if (hyps.empty()) {
      h = Refine(parent, child, sift_corr, st.pose, threshold, angular, options, cancel);
    } else {
      h = Refine(parent, child, sift_corr, st.pose, threshold, angular, screen, cancel);
      double top = 0.0;
      for (const Hypothesis& o : hyps) top = std::max(top, Score(o));
      if (Score(h) >= 0.5 * options.coarse.ambiguity_ratio * top) {
        h = Refine(parent, child, sift_corr, h.parent_from_child, threshold, angular, options, cancel);
      } else {
        h.screened_only = true;
      }
    }
    hyps.push_back(h);
    hyp_from_plan.push_back(st.from_plan);
  }
  if (cancel.IsCancelled()) return fail("cancelled");
  // Best score first; poses that free space rules out (FreerThan) are neither chosen nor rivals. A
  // pose only screened that free space puts first is refined in full, and the poses ranked again.
  std::vector<int> rank;
  while (true) {  // ends: each pass refines a pose only screened, or stops
    rank.clear();
    for (std::size_t k = 0; k < hyps.size(); ++k) {
      bool ruled_out = false;
      for (const Hypothesis& other : hyps) ruled_out |= Fits(options.thresholds, other) && FreerThan(other, hyps[k]);
      if (!ruled_out) rank.push_back(static_cast<int>(k));
    }
    std::stable_sort(rank.begin(), rank.end(), [&](int a, int b) { return Score(hyps[a]) > Score(hyps[b]); });
    Hypothesis& first = hyps[rank[0]];
    if (!first.screened_only) break;
    first = Refine(parent, child, sift_corr, first.parent_from_child, threshold, angular, options, cancel);
  }
  const Hypothesis& best = hyps[rank[0]];
  if (!best.evidence.unavailable.empty()) return fail(best.evidence.unavailable);
  const bool best_from_plan = hyp_from_plan[rank[0]];
  if (best_from_plan) {
    link.method = "plan+" + std::string(FineMethodName(options.fine)) + " levelled";
    result.coarse_parent_from_child = starts[rank[0]].pose;
    result.coarse_ok = true;
  }
  link.parent_from_child = best.parent_from_child;
  link.iterations += best.iterations;
  link.overlap = best.evidence.overlap;
  link.rms_m = best.evidence.rms_m;
  link.conflict = best.evidence.conflict;
  link.moving = best.evidence.moving;
  result.violation_rate = best.evidence.ViolationRate();
  const std::vector<int> geometric_consistent = ConsistentIndices(geometric_corr, best.parent_from_child, threshold);
  link.consistent = static_cast<int>(ConsistentIndices(sift_corr, best.parent_from_child, threshold, angular).size() +
                                     geometric_consistent.size());  // FPFH: their own tolerances
  int coarse_consistent = 0;  // of them, coarse-scale FPFH (GeometricOptions::coarse_scale)
  for (int k : geometric_consistent) coarse_consistent += geometric[k].child >= child.geometric.FinestEnd();
  // The best distinct competitor. Ambiguous only when both poses fit well; when neither does, the
  // evidence below fails the link.
  const Hypothesis* rival = nullptr;
  for (std::size_t k = 1; k < rank.size() && !rival; ++k)
    if (Distinct(best.parent_from_child, hyps[rank[k]].parent_from_child, options.coarse)) rival = &hyps[rank[k]];
  if (rival && Score(best) >= options.thresholds.weak_overlap &&
      Score(*rival) >= options.coarse.ambiguity_ratio * Score(best)) {
    const Eigen::Isometry3d rival_from_best = rival->parent_from_child.inverse() * best.parent_from_child;
    return fail(Format("ambiguous: a pose %.2f m away", rival_from_best.translation().norm()) +
                Format(" and turned %.0f° fits the surfaces almost as well (score %.2f against ",
                       RotationAngle(rival_from_best.linear()) * 180.0 / M_PI, Score(*rival)) +
                Format("%.2f here: overlap discounted by free-space conflicts); repeated structure — set the parent by hand",
                       Score(best)));
  }
  // A pose that a plan-view start also reached is judged as a plan-view pose when too few
  // correspondences confirm it (sparse stations: the features are not where the evidence is).
  bool plan_supported = best_from_plan;
  for (std::size_t k = 0; k < hyps.size(); ++k)
    plan_supported |= hyp_from_plan[k] && !Distinct(best.parent_from_child, hyps[k].parent_from_child, options.coarse);
  if (!best_from_plan && (!plan_supported || link.consistent >= coarse->required_inliers)) {
    Classify(options.thresholds, coarse->required_inliers, link);
    if (link.status == io::LinkStatus::kOk && coarse->ambiguous) {
      link.status = io::LinkStatus::kWeak;
      link.reason = "features were ambiguous (" + coarse->reason + "); the surfaces decided";
    }
    // Support near the chance model's floor: a chance consensus looks the same (real RGB-D
    // fragments: two wrong poses with 12 and 13 consistent correspondences, a right one with 11).
    result.weak_support = link.status == io::LinkStatus::kWeak &&
                          (coarse->ambiguous || link.consistent < options.thresholds.weak_inliers);
    // Evidence that adds up (issue 37): few correspondences, but surfaces that would carry a pose
    // on their own — twice the overlap that makes a link weak, free space tested and clear, the RMS
    // at the noise, no other pose fitting, not a twin spot — confirm it without a loop. Measured: an
    // isolated pair 5 m apart on a static street, 14 consistent correspondences, 65 % overlap,
    // 13.9 mm RMS at 12 mm noise, no conflict, was left "not verified"; the kitchen's wrong poses
    // (12-13 correspondences) overlapped 9 % and were point lists, where free space is not tested.
    if (result.weak_support && !coarse->ambiguous && best.evidence.tested > 0 &&
        link.overlap >= 2 * options.thresholds.weak_overlap &&  // weak, so SurfaceFailure passed (Classify)
        SurfaceWeakness(options.thresholds, link).empty() && link.moving <= options.thresholds.weak_conflict &&
        !(rival && Score(*rival) >= 0.5 * Score(best)) &&
        !OtherFittingPose(options.thresholds, best, hyps, rank, options.coarse) &&
        !SameSpot(parent, child, best.parent_from_child, 0.2)) {
      result.weak_support = false;
      link.reason += Format(", but the surfaces agree: %.0f %% overlap", 100 * link.overlap) +
                     Format(" at %.1f mm RMS, %.2f %% in the other scanner's free space, no other pose fits",
                            1000 * link.rms_m, 100 * link.conflict);
    }
    // Points in the other scanner's free space are evidence against the pose, not just a lack of
    // evidence for it: a weak link with static conflicts places a scan only when a loop through
    // other scans confirms it (issue 38: a room fits another room turned 180° with 9-12 consistent
    // correspondences, 84 % overlap and 4.2-4.8 % conflict — the furniture that differs).
    // The same for a weak pose that rests on coarse-scale features with object-sized conflicts beyond
    // what would fail a link if they were static (issue 37): the cars and posts of a symmetric street
    // turned 180° (measured: 12 consistent coarse-scale correspondences, 1.0 % static and 24.6 %
    // object-sized conflict, 25 m off). Fine-scale support keeps its traffic (5 m spacing, 8
    // vehicles: ~10 % at the true poses).
    const bool coarse_supported = link.consistent - coarse_consistent < coarse->required_inliers;
    if (link.status == io::LinkStatus::kWeak && link.conflict > options.thresholds.weak_conflict) {
      link.reason += Format("; %.1f %% of the points lie in the other scanner's free space; a loop confirms it",
                            100 * link.conflict);
      result.needs_loop_if_checkable = true;
    } else if (link.status == io::LinkStatus::kWeak && coarse_supported && link.moving > options.thresholds.max_conflict) {
      link.reason += Format("; %.1f %% of the points lie in the other scanner's free space on object-sized "
                            "clusters (traffic, or a wrong pose); a loop confirms it",
                            100 * link.moving);
      result.needs_loop_if_checkable = true;
    }
    // Features of repeated doors and rooms agree on a station's twin spot as readily as on its own
    // (measured on a symmetric office floor: 16-31 consistent correspondences, 83-95 % overlap, no
    // conflict, scanners 0.03-0.12 of their median range apart, all 8 stations placed on 2 spots;
    // loops close through such poses as readily, so a loop cannot confirm one). Two scans from one
    // tripod setup (a rescan) are nearer than 2 cm and stay linked.
    const double apart_m = best.parent_from_child.translation().norm();
    if (link.status != io::LinkStatus::kFailed && apart_m >= 0.02 &&
        SameSpot(parent, child, best.parent_from_child, 0.15)) {
      link.status = io::LinkStatus::kFailed;
      link.reason = Format("both scanners at one spot (%.2f m apart): a repeated room or corridor fits itself "
                           "there — keep the link by hand if both scans were taken there",
                           apart_m);
      // A look-alike spot that free space refutes is no twin (FreeSpaceRefutes).
      result.same_spot = best.evidence.ViolationRate() < kClearViolationRate;
    }
    return finish();
  }
  result.surfaces_only = true;
  // A plan-view pose: the surfaces are its only evidence, so they must be clear — what would make
  // a feature-supported link weak fails it (two similar streets far apart can overlap 10 % at a
  // plan-view pose), and so does a close second pose.
  if (!best_from_plan) link.method += " (plan-view confirmed)";
  std::string reason;
  if (!(reason = SurfaceFailure(options.thresholds, link)).empty() ||
      !(reason = SurfaceWeakness(options.thresholds, link)).empty()) {
    link.status = io::LinkStatus::kFailed;
    link.reason = "plan-view pose without feature support: " + reason;
  } else if (rival && Score(*rival) >= 0.5 * Score(best)) {
    link.status = io::LinkStatus::kFailed;
    link.reason = Format("plan-view pose without feature support, and a second pose nearly as good (score %.2f vs ",
                         Score(*rival)) +
                  Format("%.2f)", Score(best));
  } else if (const Hypothesis* other = OtherFittingPose(options.thresholds, best, hyps, rank, options.coarse)) {
    const Eigen::Isometry3d other_from_best = other->parent_from_child.inverse() * best.parent_from_child;
    link.status = io::LinkStatus::kFailed;
    link.reason = Format("plan-view pose without feature support, and a pose %.2f m away",
                         other_from_best.translation().norm()) +
                  Format(" and turned %.0f° fits the surfaces too", RotationAngle(other_from_best.linear()) * 180.0 / M_PI) +
                  Format(" (overlap %.1f %% there, ", 100 * other->evidence.overlap) +
                  Format("%.1f %% here, neither in the other scanner's free space): a symmetric or repeated layout", 100 * best.evidence.overlap);
  } else if (SameSpot(parent, child, best.parent_from_child, 0.2) && best.evidence.ViolationRate() >= kClearViolationRate) {
    // A look-alike spot that free space refutes (FreeSpaceRefutes) is no twin: measured on an
    // office floor, corridor stations on each other's spots left 0.57-1.71 % of the samples in free
    // space (the corridor's far ends, the rooms seen through the doors), true poses 0.01-0.05 %.
    link.status = io::LinkStatus::kFailed;
    link.reason = Format("plan-view pose without feature support that puts both scanners at one spot (%.2f m apart) "
                         "with %.2f %% of the samples in the other scanner's free space: a repeated corridor or room",
                         best.parent_from_child.translation().norm(), 100 * best.evidence.ViolationRate());
  } else if (SameSpot(parent, child, best.parent_from_child, 0.2)) {
    // A corridor or a row of rooms fits itself at its own spot, turned 180° or slid by a door
    // (measured: an office floor's end stations, 24.7 m apart, placed on each other with 82 %
    // overlap and no conflict): without features, a loop must say which spot.
    link.status = io::LinkStatus::kWeak;
    link.reason = Format("plan-view pose without feature support that puts both scanners at one spot (%.2f m "
                         "apart): a corridor or a row of rooms fits itself there; a loop confirms it",
                         best.parent_from_child.translation().norm());
    result.needs_loop = true;
    result.same_spot = true;
  } else if (link.conflict > options.thresholds.plan_view_conflict) {
    // Static conflicts: a true pose leaves almost none (LinkThresholds::plan_view_conflict). After
    // the twin-spot rules above: a loop closes through a twin pose as readily as through the truth.
    // Object-sized conflicts do not count here: they are clusters that stand out of the other
    // scan's range image (visibility.h), traffic at a true pose. (Before clusters attached to
    // surfaces counted as static, they also took in the corridor end walls of office poses slid
    // or turned; a plan-view pose with object-sized conflicts then needed a loop, and a busy street
    // at 12 m, whose every link carried 2-10 % traffic, registered 3 of 6 scans where every link
    // was right. Measured on the 18 regression projects at 1000 x 250: plan-view poses with over
    // 2 % object-sized and at most 0.5 % static conflict, 41 right and none wrong.) A 180° turn of
    // a symmetric street also moves façade parts into free space (measured: 1.3 % static): this rule.
    link.status = io::LinkStatus::kWeak;
    link.reason = Format("plan-view pose without feature support; %.1f %% of the points lie in the other "
                         "scanner's free space, where a true pose leaves almost none; a loop confirms it",
                         100 * link.conflict);
    result.needs_loop = true;
  } else {
    link.status = io::LinkStatus::kOk;
    link.reason.clear();
  }
  return finish();
}

}  // namespace scanreg::pipeline
