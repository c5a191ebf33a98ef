#include "core/registration/coarse.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>

#include "core/geometry/transform.h"
#include "core/registration/epnp_pose.h"
#include "core/registration/rigid_fit.h"

namespace scanreg {
namespace {

struct Score {
  int support = 0;
  double cost = std::numeric_limits<double>::infinity();  // MSAC: sum of min(d^2, thr^2)
  bool BetterThan(const Score& o) const { return support > o.support || (support == o.support && cost < o.cost); }
};

double Tolerance(const Correspondence3d& x, double thr) { return x.tolerance_m > 0.0 ? x.tolerance_m : thr; }

Score ScorePose(const std::vector<Correspondence3d>& c, const Eigen::Isometry3d& pose, double thr) {
  Score s;
  s.cost = 0.0;
  for (const auto& x : c) {
    const double t = Tolerance(x, thr);
    const double d2 = (x.parent - pose * x.child).squaredNorm();
    if (d2 < t * t) ++s.support;
    s.cost += std::min(d2, t * t) / (t * t);  // normalised: sources with other tolerances weigh alike
  }
  return s;
}

std::vector<int> Inliers(const std::vector<Correspondence3d>& c, const Eigen::Isometry3d& pose, double thr) {
  std::vector<int> out;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double t = Tolerance(c[i], thr);
    if ((c[i].parent - pose * c[i].child).squaredNorm() < t * t) out.push_back(static_cast<int>(i));
  }
  return out;
}

bool Distinct(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const CoarseOptions& o) {
  return (a.translation() - b.translation()).norm() > o.ambiguity_distance_m ||
         RotationAngle(a.linear().transpose() * b.linear()) > o.ambiguity_angle_rad;
}

int SampleSize(const CoarseOptions& o) {
  if (o.method == CoarseMethod::kEpnp) return o.sample_size_epnp;
  return o.levelled ? 2 : 3;
}

// Hypotheses needed so that an all-inlier sample occurs with probability `confidence`.
long RequiredIterations(double inlier_fraction, int sample_size, double confidence, long cap) {
  inlier_fraction = std::clamp(inlier_fraction, 0.0, 1.0);
  const double p_good = std::pow(inlier_fraction, sample_size);
  if (p_good >= 1.0) return 1;
  if (p_good <= 0.0) return cap;
  const double n = std::log(1.0 - confidence) / std::log(1.0 - p_good);
  return static_cast<long>(std::min<double>(cap, std::ceil(n)));
}

struct PassResult {
  std::optional<Eigen::Isometry3d> pose;
  Score score;
  int iterations = 0;
  bool cancelled = false;
};

// One RANSAC pass. Samples from `pool`, scores on all correspondences. `target_fraction` < 0: the
// adaptive count follows the best hypothesis's inlier fraction in the pool; otherwise the count is
// fixed by that fraction (the competitor search). `reject` drops hypotheses (not distinct enough).
template <typename Reject>
PassResult RunPass(const std::vector<Correspondence3d>& c, const std::vector<int>& pool, const CoarseOptions& o,
                   std::mt19937_64& rng, const CancelToken& cancel, double target_fraction, Reject reject) {
  PassResult out;
  const bool epnp = o.method == CoarseMethod::kEpnp;
  const int s = SampleSize(o);
  const int m = static_cast<int>(pool.size());
  if (m < s) return out;
  long needed = target_fraction >= 0.0 ? RequiredIterations(target_fraction, s, o.confidence, o.max_iterations)
                                       : o.max_iterations;
  std::vector<int> sample(s);
  std::vector<Eigen::Vector3d> sp(s), sc(s);
  std::vector<char> in_pool(c.size(), 0);
  for (int i : pool) in_pool[i] = 1;
  for (long it = 0; it < needed; ++it) {
    if (cancel.IsCancelled()) {
      out.cancelled = true;
      return out;
    }
    ++out.iterations;
    for (int k = 0; k < s; ++k) {  // s distinct indices, uniform over the pool
      int idx;
      do {
        idx = pool[rng() % static_cast<std::uint64_t>(m)];
      } while (std::find(sample.begin(), sample.begin() + k, idx) != sample.begin() + k);
      sample[k] = idx;
    }
    std::optional<Eigen::Isometry3d> pose;
    if (epnp) {
      // A point in front of the virtual camera first: it fixes EPnP's sign (virtual_plane.h).
      auto front = std::find_if(sample.begin(), sample.end(), [&](int i) { return c[i].child.x() > 0.0; });
      if (front == sample.end()) continue;
      std::iter_swap(sample.begin(), front);
      for (int k = 0; k < s; ++k) {
        sp[k] = c[sample[k]].parent;
        sc[k] = c[sample[k]].child;
      }
      pose = EpnpParentFromChild(sp, sc, o.focal);
    } else {
      for (int k = 0; k < s; ++k) {
        sp[k] = c[sample[k]].parent;
        sc[k] = c[sample[k]].child;
      }
      if (o.levelled) {
        pose = FitHeading(sc, sp);
      } else if (auto fit = FitRigid(sc, sp); fit.ok()) {
        pose = *fit;
      }
    }
    if (!pose || reject(*pose)) continue;
    const Score score = ScorePose(c, *pose, o.inlier_threshold_m);
    if (!out.pose || score.BetterThan(out.score)) {
      out.pose = pose;
      out.score = score;
      if (target_fraction < 0.0) {
        int in_pool_support = 0;
        for (int i : Inliers(c, *pose, o.inlier_threshold_m)) in_pool_support += in_pool[i];
        needed = std::min(needed, RequiredIterations(double(in_pool_support) / m, s, o.confidence, o.max_iterations));
      }
    }
  }
  return out;
}

// A refit on the inliers, re-scored, repeated while the support grows (local optimisation):
// heading + translation for levelled scans, then 6-DoF where that keeps the support.
void Refine(const std::vector<Correspondence3d>& c, double thr, bool levelled, Eigen::Isometry3d& pose, Score& score) {
  for (int pass = levelled ? 0 : 1; pass < 2; ++pass) {
    for (int round = 0; round < 10; ++round) {
      const std::vector<int> in = Inliers(c, pose, thr);
      std::vector<Eigen::Vector3d> src, dst;
      std::vector<double> weights;  // 1 / tolerance^2: the better localised sources count more
      for (int i : in) {
        src.push_back(c[i].child);
        dst.push_back(c[i].parent);
        weights.push_back(1.0 / (Tolerance(c[i], thr) * Tolerance(c[i], thr)));
      }
      std::optional<Eigen::Isometry3d> fit;
      if (pass == 0) {
        fit = FitHeading(src, dst, weights);
      } else if (auto rigid = FitRigid(src, dst, weights); rigid.ok()) {
        fit = *rigid;
      }
      if (!fit) break;
      const Score s = ScorePose(c, *fit, thr);
      if (s.support < score.support || (!s.BetterThan(score) && round > 0)) break;
      pose = *fit;
      score = s;
    }
  }
}

// log of the binomial tail P[X >= k], X ~ Binomial(n, p).
double LogBinomialTail(int n, int k, double p) {
  if (k <= 0) return 0.0;
  if (k > n) return -std::numeric_limits<double>::infinity();
  double log_sum = -std::numeric_limits<double>::infinity();
  for (int j = k; j <= n; ++j) {
    const double t = std::lgamma(n + 1.0) - std::lgamma(j + 1.0) - std::lgamma(n - j + 1.0) + j * std::log(p) +
                     (n - j) * std::log1p(-p);
    const double hi = std::max(log_sum, t);
    log_sum = hi + std::log(std::exp(log_sum - hi) + std::exp(t - hi));
    if (t < log_sum - 40.0) break;  // the remaining terms shrink geometrically
  }
  return log_sum;
}

}  // namespace

Status CoarseOptions::Validate() const {
  auto bad = [](const std::string& m) { return Status(MakeError(ErrorCode::kInvalidArgument, "coarse registration: " + m)); };
  if (sample_size_epnp < 4) return bad("sample_size_epnp must be >= 4 (EPnP needs 4 points), got " + std::to_string(sample_size_epnp));
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(confidence > 0.0 && confidence < 1.0)) return bad("confidence must be in (0, 1)");
  if (!(inlier_threshold_m > 0.0) || !std::isfinite(inlier_threshold_m)) return bad("inlier_threshold_m must be > 0 metres");
  if (!(max_false_pose_probability > 0.0 && max_false_pose_probability < 1.0))
    return bad("max_false_pose_probability must be in (0, 1)");
  if (levelled && method == CoarseMethod::kEpnp) return bad("the levelled (4-DoF) solver needs the 3D method");
  if (!(ambiguity_ratio > 0.0 && ambiguity_ratio <= 1.0)) return bad("ambiguity_ratio must be in (0, 1]");
  if (!(ambiguity_distance_m > 0.0)) return bad("ambiguity_distance_m must be > 0 metres");
  if (!(ambiguity_angle_rad > 0.0)) return bad("ambiguity_angle_rad must be > 0");
  if (!(focal > 0.0) || !std::isfinite(focal)) return bad("focal must be > 0 pixels");
  return Status::Ok();
}

int RequiredInliers(int n, int sample_size, long hypotheses, double inlier_threshold_m,
                    const std::vector<Correspondence3d>& correspondences, double max_false_pose_probability) {
  const int floor = sample_size + 2;
  // The parent points' extent, robust to stray points: 5th to 95th percentile per axis.
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  if (!correspondences.empty()) {
    for (int a = 0; a < 3; ++a) {
      std::vector<double> v;
      for (const Correspondence3d& x : correspondences)
        if (x.parent.allFinite()) v.push_back(x.parent[a]);
      if (v.empty()) continue;
      std::sort(v.begin(), v.end());
      size[a] = v[static_cast<std::size_t>(0.95 * (v.size() - 1))] - v[static_cast<std::size_t>(0.05 * (v.size() - 1))];
    }
  }
  std::sort(size.data(), size.data() + 3);
  double widest = inlier_threshold_m;  // the chance of a stray agreement grows with the tolerance
  for (const Correspondence3d& x : correspondences) widest = std::max(widest, x.tolerance_m);
  const double disc = M_PI * widest * widest;
  const double area = std::max(size[2] * size[1], disc);
  const double p = std::clamp(2.0 * disc / area, 1e-12, 0.5);
  const double log_budget = std::log(max_false_pose_probability) - std::log(std::max(1L, hypotheses));
  for (int k = floor; k <= n; ++k)
    if (LogBinomialTail(n - sample_size, k - sample_size, p) <= log_budget) return k;
  return n + 1;  // no support would be convincing
}

Expected<CoarseResult> EstimateCoarse(const std::vector<Correspondence3d>& correspondences,
                                      const CoarseOptions& options, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const auto& c = correspondences;
  const int n = static_cast<int>(c.size());
  const bool epnp = options.method == CoarseMethod::kEpnp;
  const int s = SampleSize(options);
  const int needed = s + 2;
  if (n < needed)
    return MakeError(ErrorCode::kFailed, "coarse registration needs at least " + std::to_string(needed) +
                                             " correspondences, got " + std::to_string(n));
  // EPnP samples only pairs whose child point has a usable image (< ~87° off the optical axis).
  std::vector<int> pool;
  for (int i = 0; i < n; ++i) {
    if (!c[i].parent.allFinite() || !c[i].child.allFinite()) continue;
    if (!epnp || std::abs(c[i].child.x()) >= 0.05 * c[i].child.norm()) pool.push_back(i);
  }
  std::mt19937_64 rng(options.seed);
  auto no_reject = [](const Eigen::Isometry3d&) { return false; };
  PassResult best = RunPass(c, pool, options, rng, cancel, -1.0, no_reject);
  if (best.cancelled) return MakeError(ErrorCode::kCancelled, "coarse registration cancelled");
  CoarseResult out;
  out.iterations = best.iterations;
  if (!best.pose)
    return MakeError(ErrorCode::kFailed, "coarse registration found no pose from " + std::to_string(n) +
                                             " correspondences (" + std::to_string(pool.size()) + " usable for sampling)");
  Refine(c, options.inlier_threshold_m, options.levelled, *best.pose, best.score);
  out.parent_from_child = *best.pose;
  out.inlier_indices = Inliers(c, out.parent_from_child, options.inlier_threshold_m);
  out.inliers = static_cast<int>(out.inlier_indices.size());
  double sum2 = 0.0;
  for (int i : out.inlier_indices) sum2 += (c[i].parent - out.parent_from_child * c[i].child).squaredNorm();
  out.rms_m = out.inliers ? std::sqrt(sum2 / out.inliers) : 0.0;
  const int min_count = RequiredInliers(n, s, out.iterations, options.inlier_threshold_m, c,
                                        options.max_false_pose_probability);
  out.required_inliers = min_count;
  if (out.inliers < min_count)
    return MakeError(ErrorCode::kFailed, "coarse registration: only " + std::to_string(out.inliers) + " of " +
                                             std::to_string(n) + " correspondences agree on a pose (need " +
                                             std::to_string(min_count) + ")");

  // Competitor search among the best pose's outliers (repeated façades give a second pose).
  std::vector<char> is_inlier(n, 0);
  for (int i : out.inlier_indices) is_inlier[i] = 1;
  std::vector<int> rest;
  for (int i : pool)
    if (!is_inlier[i]) rest.push_back(i);
  const double target = std::min(1.0, options.ambiguity_ratio * out.inliers / std::max<std::size_t>(rest.size(), 1));
  auto near_best = [&](const Eigen::Isometry3d& p) { return !Distinct(p, out.parent_from_child, options); };
  PassResult second = RunPass(c, rest, options, rng, cancel, target, near_best);
  out.iterations += second.iterations;
  if (second.cancelled) return MakeError(ErrorCode::kCancelled, "coarse registration cancelled");
  if (second.pose) {
    out.competitor = second.pose;
    out.competitor_support = second.score.support;
  }
  if (second.pose && second.score.support >= options.ambiguity_ratio * out.inliers) {
    out.ambiguous = true;
    const Eigen::Isometry3d d = out.parent_from_child.inverse() * *second.pose;
    char buf[256];
    std::snprintf(buf, sizeof(buf),
                  "ambiguous: a second pose %.2f m / %.1f deg away has %d supporting correspondences vs %d for the "
                  "best (repeated structure such as façades?)",
                  (second.pose->translation() - out.parent_from_child.translation()).norm(),
                  RotationAngle(d.linear()) * 180.0 / 3.14159265358979323846, second.score.support, out.inliers);
    out.reason = buf;
  }
  return out;
}

}  // namespace scanreg
