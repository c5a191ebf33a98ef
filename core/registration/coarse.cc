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

Score ScorePose(const std::vector<Correspondence3d>& c, const Eigen::Isometry3d& pose, double thr) {
  Score s;
  s.cost = 0.0;
  const double t2 = thr * thr;
  for (const auto& x : c) {
    const double d2 = (x.parent - pose * x.child).squaredNorm();
    if (d2 < t2) ++s.support;
    s.cost += std::min(d2, t2);
  }
  return s;
}

std::vector<int> Inliers(const std::vector<Correspondence3d>& c, const Eigen::Isometry3d& pose, double thr) {
  std::vector<int> out;
  for (std::size_t i = 0; i < c.size(); ++i)
    if ((c[i].parent - pose * c[i].child).squaredNorm() < thr * thr) out.push_back(static_cast<int>(i));
  return out;
}

bool Distinct(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const CoarseOptions& o) {
  return (a.translation() - b.translation()).norm() > o.ambiguity_distance_m ||
         RotationAngle(a.linear().transpose() * b.linear()) > o.ambiguity_angle_rad;
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
  const int s = epnp ? o.sample_size_epnp : 3;
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
      auto fit = FitRigid(sc, sp);
      if (fit.ok()) pose = *fit;
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

// FitRigid on the inliers, re-scored, while the support grows (local optimisation).
void Refine(const std::vector<Correspondence3d>& c, double thr, Eigen::Isometry3d& pose, Score& score) {
  for (int round = 0; round < 10; ++round) {
    const std::vector<int> in = Inliers(c, pose, thr);
    std::vector<Eigen::Vector3d> src, dst;
    for (int i : in) {
      src.push_back(c[i].child);
      dst.push_back(c[i].parent);
    }
    auto fit = FitRigid(src, dst);
    if (!fit.ok()) return;
    const Score s = ScorePose(c, *fit, thr);
    if (!s.BetterThan(score) && round > 0) return;
    if (s.support < score.support) return;
    pose = *fit;
    score = s;
  }
}

}  // namespace

Status CoarseOptions::Validate() const {
  auto bad = [](const std::string& m) { return Status(MakeError(ErrorCode::kInvalidArgument, "coarse registration: " + m)); };
  if (sample_size_epnp < 4) return bad("sample_size_epnp must be >= 4 (EPnP needs 4 points), got " + std::to_string(sample_size_epnp));
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(confidence > 0.0 && confidence < 1.0)) return bad("confidence must be in (0, 1)");
  if (!(inlier_threshold_m > 0.0) || !std::isfinite(inlier_threshold_m)) return bad("inlier_threshold_m must be > 0 metres");
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0)) return bad("min_inlier_ratio must be in [0, 1]");
  if (min_inliers < 3) return bad("min_inliers must be >= 3");
  if (!(ambiguity_ratio > 0.0 && ambiguity_ratio <= 1.0)) return bad("ambiguity_ratio must be in (0, 1]");
  if (!(ambiguity_distance_m > 0.0)) return bad("ambiguity_distance_m must be > 0 metres");
  if (!(ambiguity_angle_rad > 0.0)) return bad("ambiguity_angle_rad must be > 0");
  if (!(focal > 0.0) || !std::isfinite(focal)) return bad("focal must be > 0 pixels");
  return Status::Ok();
}

Expected<CoarseResult> EstimateCoarse(const std::vector<Correspondence3d>& correspondences,
                                      const CoarseOptions& options, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const auto& c = correspondences;
  const int n = static_cast<int>(c.size());
  const bool epnp = options.method == CoarseMethod::kEpnp;
  const int s = epnp ? options.sample_size_epnp : 3;
  const int needed = std::max(s, options.min_inliers);
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
  Refine(c, options.inlier_threshold_m, *best.pose, best.score);
  out.parent_from_child = *best.pose;
  out.inlier_indices = Inliers(c, out.parent_from_child, options.inlier_threshold_m);
  out.inliers = static_cast<int>(out.inlier_indices.size());
  double sum2 = 0.0;
  for (int i : out.inlier_indices) sum2 += (c[i].parent - out.parent_from_child * c[i].child).squaredNorm();
  out.rms_m = out.inliers ? std::sqrt(sum2 / out.inliers) : 0.0;
  const int min_count = std::max(options.min_inliers, static_cast<int>(std::ceil(options.min_inlier_ratio * n)));
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
