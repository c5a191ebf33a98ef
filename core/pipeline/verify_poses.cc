#include "core/pipeline/verify_poses.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/common/log.h"
#include "core/pipeline/registration_driver.h"
#include "core/registration/multiview.h"

namespace scanreg::pipeline {
namespace {

std::string Mm(double m) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f mm", 1e3 * m);
  return buf;
}

// Marks the link that placed scan `child` failed (it is not used) with the reason.
void FailPlacingLink(const std::vector<Scan>& scans, int child, const std::string& reason, ProjectRegistration* result) {
  const int parent = result->scans[child].parent;
  if (parent < 0) return;
  for (io::LinkRecord& l : result->links)
    if (!l.loop_check && l.parent == scans[parent].name && l.child == scans[child].name &&
        l.status != io::LinkStatus::kFailed) {
      l.status = io::LinkStatus::kFailed;
      l.reason = reason;
    }
}

}  // namespace

Status VerifyAgainstStart(const std::vector<Scan>& scans, const std::vector<std::vector<Eigen::Vector3d>>& samples,
                          const ScanOrderChoices& choices, const VerifyOptions& options, ProgressSink& progress,
                          const CancelToken& cancel, ProjectRegistration* result) {
  const int n = static_cast<int>(scans.size());
  if (n < 2 || result->root < 0) return Status::Ok();
  progress.Report(0.0, "checking the poses against every overlap");
  std::vector<ViewSurface> surfaces(n);
  std::vector<const ViewSurface*> views(n);
  for (int i = 0; i < n; ++i) {
    surfaces[i] = MakeViewSurface(samples[i]);
    views[i] = &surfaces[i];
  }
  Poses start(n), pairwise(n);
  std::vector<bool> registered(n), all(n, true);
  for (int i = 0; i < n; ++i) {
    start[i] = scans[i].world_from_scan;
    registered[i] = result->scans[i].registered;
    pairwise[i] = registered[i] ? result->scans[i].world_from_scan : start[i];
  }
  Poses taken = pairwise;
  const double scale = options.scale_factor * options.cutoff_m;  // the bounded loss's scale
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");

  // The multi-view fine step over the registered scans, from the pairwise result.
  Poses multiview;
  if (options.multiview) {
    progress.Report(0.2, "multi-view fine step");
    const auto mv_pairs = OverlappingPairs(views, {pairwise}, registered, options.evidence_m, options.min_overlap);
    std::vector<bool> fixed(n, false);
    for (int i = 0; i < n; ++i) fixed[i] = !registered[i] || i == result->root;
    MultiViewOptions mo;
    mo.cutoff_m = options.evidence_m;
    mo.floor_m = 3 * options.noise_m;
    mo.converged_m = 0.1 * options.noise_m;
    Expected<MultiViewResult> mv = AlignMultiView(views, pairwise, mv_pairs, fixed, mo, cancel);
    if (!mv) return mv.error();
    multiview = mv->world;
    char buf[160];
    std::snprintf(buf, sizeof buf, "multi-view fine step: %zu overlapping pairs, %d rounds%s", mv_pairs.size(),
                  mv->rounds, mv->converged ? "" : " (not converged)");
    LogInfo(buf);
  }

  // One set of pairs and samples for every comparison: the pairs overlapping at any of the poses.
  std::vector<Poses> sets = {start, pairwise};
  if (!multiview.empty()) sets.push_back(multiview);
  const auto pairs = OverlappingPairs(views, sets, all, options.evidence_m, options.min_overlap);
  progress.Report(0.6, "measuring the consistency of " + std::to_string(pairs.size()) + " overlapping pairs");
  std::vector<Consistency> measured = MeasureConsistency(views, sets, pairs, options.cutoff_m, scale);
  io::ConsistencyRecord& check = result->consistency.emplace();
  check.cutoff_m = options.cutoff_m;
  check.pairs = static_cast<int>(pairs.size());
  Consistency current = measured[1];
  if (!multiview.empty()) {
    if (measured[2].rms_m <= measured[1].rms_m) {
      taken = multiview;
      current = measured[2];
      check.multiview = true;
    } else {
      LogWarning("the multi-view fine step left the project less consistent (" + Mm(measured[1].rms_m) + " -> " +
                 Mm(measured[2].rms_m) + "); the pairwise result is kept");
    }
  }
  // The user's links hold exactly.
  for (int i = 0; i < n; ++i)
    if (registered[i]) result->scans[i].world_from_scan = taken[i];
  HoldKeptLinks(choices, result);
  for (int i = 0; i < n; ++i)
    if (registered[i]) taken[i] = result->scans[i].world_from_scan;

  // Each scan no worse than at its start pose, the worst first. Every comparison is made on the
  // samples of all the pose sets above and the poses taken now, so the start's figures stay comparable.
  auto held_by_user = [&](int i) {  // the user's link is never undone
    for (const auto& [edge, link] : choices.kept)
      if (edge.second == i) return true;
    return false;
  };
  auto measure_taken = [&](Consistency* at_start, Consistency* now) {
    std::vector<Poses> with_taken = sets;
    with_taken.push_back(taken);
    std::vector<Consistency> c = MeasureConsistency(views, with_taken, pairs, options.cutoff_m, scale);
    *at_start = std::move(c.front());
    *now = std::move(c.back());
  };
  Consistency at_start = measured[0];
  auto worse = [&](const Consistency& c, int i) {
    return c.scan_samples[i] > 0 && c.scan_rms_m[i] > 1.05 * at_start.scan_rms_m[i] + 0.25 * options.noise_m;
  };
  for (int round = 0; round < n; ++round) {
    int worst = -1;
    double ratio = 1.0;
    for (int i = 0; i < n; ++i) {
      if (!registered[i] || i == result->root || taken[i].isApprox(start[i], 1e-12) || !worse(current, i) ||
          held_by_user(i))
        continue;
      const double r = current.scan_rms_m[i] / std::max(at_start.scan_rms_m[i], 1e-12);
      if (r > ratio) ratio = r, worst = i;
    }
    if (worst < 0) break;
    const std::string why = "its link disagrees with its other overlaps: robust RMS " + Mm(current.scan_rms_m[worst]) +
                            " against " + Mm(at_start.scan_rms_m[worst]) + " at its start pose; the start pose is kept";
    LogWarning(scans[worst].name + ": " + why);
    FailPlacingLink(scans, worst, why, result);
    taken[worst] = start[worst];
    result->scans[worst].world_from_scan = start[worst];
    measure_taken(&at_start, &current);
  }
  // The whole no worse than the start.
  check.start_rms_m = at_start.rms_m;
  if (current.rms_m > check.start_rms_m) {
    LogWarning("the refinement left the project less consistent than its start poses (robust RMS " +
               Mm(check.start_rms_m) + " -> " + Mm(current.rms_m) + " over " + std::to_string(pairs.size()) +
               " overlapping pairs); every scan keeps its start pose");
    check.refused = true;
    taken = start;
    for (int i = 0; i < n; ++i) result->scans[i].world_from_scan = start[i];
    current = at_start;
  }
  check.result_rms_m = current.rms_m;

  // Registered means verified.
  progress.Report(0.8, "verifying each scan");
  const auto final_pairs = OverlappingPairs(views, {taken}, registered, options.evidence_m, options.min_overlap);
  std::vector<bool> fixed(n, true);
  MultiViewOptions probe;
  probe.cutoff_m = options.evidence_m;
  probe.floor_m = 3 * options.noise_m;
  probe.rounds = 0;
  for (int i = 0; i < n; ++i) fixed[i] = i == result->root || !registered[i];
  std::vector<double> conditioning(n, -1);
  if (Expected<MultiViewResult> c = AlignMultiView(views, taken, final_pairs, fixed, probe, cancel)) conditioning = c->conditioning;
  // Each scan's agreement: the median over its pairs of the RMS of the residuals that meet at these
  // poses only (a misplaced neighbour spoils one of its pairs, not its median; samples that met only
  // at other poses, maybe spuriously, do not count here).
  auto agreement = [&](const Poses& poses, const std::vector<std::pair<int, int>>& pairs_here) {
    const Consistency c = MeasureConsistency(views, {poses}, pairs_here, options.cutoff_m, scale)[0];
    std::vector<double> out(n, -1.0);
    for (int i = 0; i < n; ++i) {
      std::vector<double> mine;
      for (std::size_t p = 0; p < pairs_here.size(); ++p)
        if ((pairs_here[p].first == i || pairs_here[p].second == i) && c.pair_rms_m[p] >= 0) mine.push_back(c.pair_rms_m[p]);
      if (mine.empty()) continue;
      std::nth_element(mine.begin(), mine.begin() + mine.size() / 2, mine.end());
      out[i] = mine[mine.size() / 2];
    }
    return out;
  };
  const std::vector<double> own = agreement(taken, final_pairs);
  const std::vector<double> own_start =
      agreement(start, OverlappingPairs(views, {start}, all, options.evidence_m, options.min_overlap));
  // The residual a verified scan may show: near the others' (real scanners leave calibration and
  // resampling errors well above the range noise: the bunny's pairs ~5 x) and near the noise, but
  // always well inside the cutoff, where a misplaced scan's residuals pile up.
  std::vector<double> shares;
  for (int i = 0; i < n; ++i)
    if (result->scans[i].registered && own[i] >= 0) shares.push_back(own[i]);
  std::nth_element(shares.begin(), shares.begin() + shares.size() / 2, shares.end());
  const double median_share = shares.empty() ? 0.0 : shares[shares.size() / 2];
  const double max_share = std::min(std::max(options.noise_factor * options.noise_m, options.spread_factor * median_share),
                                    0.5 * options.cutoff_m);
  for (int i = 0; i < n; ++i) {
    ScanRegistration& s = result->scans[i];
    s.start_consistency_m = own_start[i];
    s.consistency_m = own[i];
    s.conditioning = fixed[i] ? -1 : conditioning[i];
    if (!s.registered || i == result->root) continue;
    if (held_by_user(i)) continue;  // the user's decision
    int partners = 0;
    for (const auto& [a, b] : final_pairs) partners += a == i || b == i;
    std::string why;
    char buf[300];
    if (partners == 0) {
      std::snprintf(buf, sizeof buf, "not verified: at its pose it overlaps no registered scan by %.0f %% within %s",
                    100 * options.min_overlap, Mm(options.evidence_m).c_str());
      why = buf;
    } else if (s.consistency_m > max_share) {
      std::snprintf(buf, sizeof buf,
                    "not verified: its overlaps disagree (robust RMS %s; the scans' median %s, the range noise %s: "
                    "at most %s here)",
                    Mm(s.consistency_m).c_str(), Mm(median_share).c_str(), Mm(options.noise_m).c_str(),
                    Mm(max_share).c_str());
      why = buf;
    } else if (s.conditioning >= 0 && s.conditioning < options.min_conditioning) {
      std::snprintf(buf, sizeof buf,
                    "not verified: its overlaps leave a direction of its pose free (conditioning %.1e, at least %.0e): "
                    "a surface that slides on itself",
                    s.conditioning, options.min_conditioning);
      why = buf;
    }
    if (why.empty()) continue;
    LogWarning(scans[i].name + ": " + why);
    s.registered = false;
    s.unverified = true;
    s.reason = why;
  }
  char buf[300];
  std::snprintf(buf, sizeof buf,
                "consistency over %d overlapping pairs (residuals capped at %s): robust RMS %s at the start poses, %s "
                "after%s%s",
                check.pairs, Mm(check.cutoff_m).c_str(), Mm(check.start_rms_m).c_str(), Mm(check.result_rms_m).c_str(),
                check.multiview ? " (multi-view fine step)" : "", check.refused ? " — refused, start poses kept" : "");
  LogInfo(buf);
  return Status::Ok();
}

}  // namespace scanreg::pipeline
