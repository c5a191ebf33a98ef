#include "core/pipeline/register_project.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <malloc.h>
#include <map>
#include <memory>
#include <set>

#include "core/common/log.h"
#include "core/common/memory_gate.h"
#include "core/features/confusion.h"
#include "core/features/feature_cache.h"
#include "core/features/matching.h"
#include "core/geometry/transform.h"
#include "core/pipeline/candidate_pairs.h"
#include "core/pipeline/georeference_project.h"
#include "core/pipeline/pair_jobs.h"
#include "core/pipeline/refine_pair.h"
#include "core/pipeline/refine_project.h"
#include "core/registration/point_index.h"
#include "core/registration/voxel_filter.h"
#include "core/pipeline/register_pair.h"
#include "core/pipeline/registration_driver.h"
#include "core/pipeline/scale_defaults.h"
#include "core/pipeline/scan_store.h"

namespace scanreg::pipeline {
namespace {

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int IndexOf(const std::vector<Scan>& scans, const std::string& name) {
  for (std::size_t i = 0; i < scans.size(); ++i)
    if (scans[i].name == name) return static_cast<int>(i);
  return -1;
}

}  // namespace

Status PrepareScanFeatures(const Scan& scan, const RegisterOptions& options, PreparedScan* prepared, bool* cached,
                           const CancelToken& cancel) {
  if (UsesSift(options.features)) {
    Expected<ScanFeatures> f = options.feature_cache_dir.empty()
                                   ? DetectFeatures(scan, options.sift)
                                   : LoadOrDetectFeatures(scan, options.sift, options.feature_cache_dir, cached);
    if (!f) return MakeError(f.error().code, "scan '" + scan.name + "': " + f.error().message);
    prepared->features = std::move(*f);
  }
  if (UsesGeometric(options.features)) {
    Expected<GeometricFeatures> g = DetectGeometricFeatures(scan, options.geometric, cancel);
    if (!g) return MakeError(g.error().code, "scan '" + scan.name + "': " + g.error().message);
    prepared->geometric = std::move(*g);
  }
  PrepareScan(scan, options, prepared);
  return Status::Ok();
}

// The matches of a pair in both directions (parent's features as query), without duplicates:
// the ratio test is asymmetric, so the union holds more true correspondences than either side.
std::vector<FeatureMatch> BothWays(const MatchTable& table, int parent, int child) {
  std::vector<FeatureMatch> out;
  std::set<std::pair<int, int>> seen;
  if (const PairMatches* pm = table.Find(parent, child)) {
    for (const FeatureMatch& m : pm->matches)
      if (seen.insert({m.query, m.train}).second) out.push_back(m);
  }
  if (const PairMatches* pm = table.Find(child, parent)) {
    for (const FeatureMatch& m : pm->matches)
      if (seen.insert({m.train, m.query}).second) out.push_back({m.train, m.query, m.distance});
  }
  return out;
}

Expected<ScanOrderChoices> ResolveScanOrderChoices(const std::vector<Scan>& scans, const UserChoices& user,
                                                   const std::optional<std::string>& root) {
  const std::vector<std::optional<std::string>>& parent_override = user.parent_override;
  const int n = static_cast<int>(scans.size());
  ScanOrderChoices out;
  if (root) {
    out.root = IndexOf(scans, *root);
    if (*out.root < 0) return MakeError(ErrorCode::kInvalidArgument, "root scan '" + *root + "' is not in the project");
  }
  out.overrides.resize(n);
  for (int i = 0; i < n && i < static_cast<int>(parent_override.size()); ++i) {
    if (!parent_override[i]) continue;
    const int p = IndexOf(scans, *parent_override[i]);
    if (p < 0) {
      return MakeError(ErrorCode::kInvalidArgument, "scan '" + scans[i].name + "': parent override '" +
                                                        *parent_override[i] + "' is not in the project");
    }
    out.overrides[i] = p;
  }
  // A cycle of overrides, by scan name, before any expensive work.
  for (int start = 0; start < n; ++start) {
    std::string chain = scans[start].name;
    std::vector<char> seen(n, 0);
    seen[start] = 1;
    for (int cur = start; out.overrides[cur];) {
      cur = *out.overrides[cur];
      chain += " -> " + scans[cur].name;
      if (seen[cur]) {
        return MakeError(ErrorCode::kInvalidArgument, "parent overrides form a cycle (scan -> parent): " + chain +
                                                          "; remove one of these overrides");
      }
      seen[cur] = 1;
    }
  }
  for (const auto& [p, c] : user.rejected) {
    const int pi = IndexOf(scans, p), ci = IndexOf(scans, c);
    if (pi >= 0 && ci >= 0) out.excluded.emplace_back(pi, ci);
  }
  for (const io::LinkRecord& l : user.kept) {
    const int pi = IndexOf(scans, l.parent), ci = IndexOf(scans, l.child);
    if (pi < 0 || ci < 0 || pi == ci || (out.root && *out.root == ci)) continue;
    if (out.overrides[ci] && *out.overrides[ci] != pi) continue;  // the override wins
    // A kept link that would close a cycle of parents is not used (the registration decides).
    bool cycle = false;
    for (int cur = pi, steps = 0; out.overrides[cur] && steps <= n; ++steps) {
      cur = *out.overrides[cur];
      cycle |= cur == ci;
    }
    if (cycle) continue;
    out.overrides[ci] = pi;
    out.kept[{pi, ci}] = l;
  }
  return out;
}

Expected<ProjectRegistration> RegisterScans(const std::vector<Scan>& scans, const UserChoices& user,
                                            const RegisterOptions& raw_options, ProgressSink& progress,
                                            const CancelToken& cancel, const PairExchange* exchange) {
  ScanStore store(scans);
  return RegisterScans(store, user, raw_options, progress, cancel, exchange);
}

Expected<ProjectRegistration> RegisterScans(ScanStore& store, const UserChoices& user,
                                            const RegisterOptions& raw_options, ProgressSink& progress,
                                            const CancelToken& cancel, const PairExchange* exchange) {
  if (Status s = raw_options.Validate(); !s) return s.error();
  const std::vector<Scan>& scans = store.heads();  // names and poses; the points come from the store
  const int n = store.size();
  NullProgress null_progress;
  if (n < 2) return MakeError(ErrorCode::kInvalidArgument, "registration needs at least two scans");
  if (raw_options.from_current_poses && exchange)
    return MakeError(ErrorCode::kInvalidArgument, "pair jobs register from features; with --coarse none (refining "
                                                  "the current poses) register in one process");
  if (raw_options.from_current_poses) {  // dense refinement of every overlapping pair: every scan at once
    if (const std::vector<Scan>* all = store.in_memory()) return RegisterFromCurrentPoses(*all, user, raw_options, progress, cancel);
    std::vector<Scan> all;
    for (int i = 0; i < n; ++i) {
      Expected<std::shared_ptr<const Scan>> s = store.Get(i);
      if (!s) return s.error();
      all.push_back(**s);
    }
    return RegisterFromCurrentPoses(all, user, raw_options, progress, cancel);
  }
  const auto t_start = std::chrono::steady_clock::now();
  ProjectRegistration result;

  // The user's choices are checked before the scans are read.
  Expected<ScanOrderChoices> choices = ResolveScanOrderChoices(scans, user, raw_options.root);
  if (!choices) return choices.error();

  // Each scan read once for its scale (when a length is left to the data) and its valid points;
  // then again (from the store, resident or not) for its features. Scans are independent: prepared
  // concurrently (issue 13, item 4), each result in its own slot, so the outcome does not depend on
  // the thread count; the first error in scan order is returned.
  auto t0 = std::chrono::steady_clock::now();
  const bool measure = NeedsScale(raw_options);
  std::vector<DataScale> scales(n);
  std::vector<Status> read_ok(n, Status::Ok());
  std::atomic<int> scans_done{0};
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < n; ++i) {
    if (cancel.IsCancelled()) continue;
    Expected<std::shared_ptr<const Scan>> scan = store.Get(i);
    if (!scan) {
      read_ok[i] = scan.error();
    } else if ((*scan)->CountValid() == 0) {
      read_ok[i] = MakeError(ErrorCode::kInvalidArgument, "scan '" + scans[i].name + "' has no valid point; remove it");
    } else if (measure) {
      scales[i] = MeasureDataScale(**scan);
    }
    const int done = ++scans_done;
    progress.Report(0.05 * done / n, "read " + std::to_string(done) + " of " + std::to_string(n) + " scans");
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");
  for (int i = 0; i < n; ++i)
    if (!read_ok[i]) return read_ok[i].error();
  const Expected<RegisterOptions> resolved = ResolveLengthsFromScales(raw_options, scales);
  if (!resolved) return resolved.error();
  const RegisterOptions& options = *resolved;

  // W §2 steps 1 and 5: features and confidence maps, once per scan; FPFH beside SIFT (issue 11).
  // SIFT's working memory (OpenCV's Gaussian and difference-of-Gaussian pyramids) counts against the
  // budget too: measured ~160 bytes a panorama pixel (10 scans of 5000x2000 on 2 threads peaked
  // 3.2 GB higher than with SIFT from the cache), so scans are prepared side by side only while
  // that fits (one always runs). A large panorama is detected strip by strip (SiftStrips): one
  // strip's pixels count.
  constexpr std::size_t kSiftBytesPerPixel = 160;
  auto sift_pixels = [&](const Scan& s) { return SiftStripPixels(s, options.sift); };
  MemoryGate sift_memory(store.budget_bytes());
  std::vector<PreparedScan> prepared(n);
  std::vector<Status> prepared_ok(n, Status::Ok());
  std::vector<char> from_cache(n, 0);
  scans_done = 0;
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < n; ++i) {
    if (cancel.IsCancelled()) continue;
    Expected<std::shared_ptr<const Scan>> scan = store.Get(i);
    if (!scan) {
      prepared_ok[i] = scan.error();
      continue;
    }
    bool cached = false;
    {
      const MemoryGate::Hold hold(sift_memory, UsesSift(options.features) ? kSiftBytesPerPixel * sift_pixels(**scan) : 0);
      prepared_ok[i] = PrepareScanFeatures(**scan, options, &prepared[i], &cached, cancel);
    }
    prepared[i].scan = nullptr;  // from here on, the store's
    prepared[i].store = &store;
    prepared[i].index = i;
    from_cache[i] = cached;
    const int done = ++scans_done;
    progress.Report(0.05 + 0.25 * done / n, "features of " + std::to_string(done) + " of " + std::to_string(n) + " scans");
  }
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");
  for (int i = 0; i < n; ++i) {
    if (!prepared_ok[i]) return prepared_ok[i].error();
    result.features_from_cache += from_cache[i];
  }
  result.seconds_features = Since(t0);
  malloc_trim(0);  // the panoramas, SIFT and FPFH work arrays of every thread are free now: return them

  // W §2 steps 2-3: matching and the confusion matrix, over the candidate pairs (issue 13, item 3:
  // every pair when options.candidates is 0); FPFH matches of the same pairs (parent i < child j).
  t0 = std::chrono::steady_clock::now();
  std::vector<std::pair<int, int>> required;  // the user's pairs: always matched
  for (int i = 0; i < n; ++i)
    if (choices->overrides[i]) required.emplace_back(*choices->overrides[i], i);
  for (const auto& [key, link] : choices->kept) required.push_back(key);
  const bool select = options.candidates > 0 && options.candidates < n - 1;
  std::vector<bool> has_features(n);
  for (int i = 0; i < n; ++i) has_features[i] = prepared[i].features.size() >= 2;
  const std::vector<std::pair<int, int>> pairs =
      CandidatePairs(select ? CandidateVotes(prepared, options.match.ratio) : Eigen::MatrixXi::Zero(n, n), has_features,
                     options.candidates, required);
  result.pairs_matched = static_cast<int>(pairs.size());
  result.pairs_possible = n * (n - 1) / 2;
  if (exchange && exchange->planned) {  // register --plan: the jobs register the pairs
    exchange->planned(options, pairs);
    result.seconds_total = Since(t_start);
    return result;
  }
  if (result.pairs_matched < result.pairs_possible)
    LogInfo("matching " + std::to_string(result.pairs_matched) + " candidate pairs of " +
            std::to_string(result.pairs_possible) + " (" + std::to_string(options.candidates) +
            " best-voted scans each, neighbours in capture order, the user's pairs)");
  std::vector<ScanFeatures> features;  // moved out: the pairs need the keypoints' 3D points only
  for (PreparedScan& p : prepared) features.push_back(std::move(p.features));
  SubProgress match_progress(progress, 0.3, 0.5);
  Expected<MatchTable> table = MatchPairs(features, pairs, options.match, match_progress, cancel);
  if (!table) return table.error();
  result.confusion = table->confusion;
  std::map<std::pair<int, int>, std::vector<GeometricMatch>> geometric_matches;
  Eigen::MatrixXi weights = result.confusion;
  if (UsesGeometric(options.features)) {
    // Every pair on its own (concurrently), then gathered in pair order.
    std::vector<std::vector<GeometricMatch>> pair_matches(pairs.size());
    std::vector<int> pair_weight(pairs.size(), 0);
#pragma omp parallel for schedule(dynamic, 4)
    for (long k = 0; k < static_cast<long>(pairs.size()); ++k) {
      if (cancel.IsCancelled()) continue;
      const auto [i, j] = pairs[k];
      pair_matches[k] = MatchGeometric(prepared[i].geometric, prepared[j].geometric);
      pair_weight[k] = GeometricWeight(prepared[i], prepared[j], pair_matches[k], options);
    }
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto [i, j] = pairs[k];
      geometric_matches[{i, j}] = std::move(pair_matches[k]);
      weights(i, j) += pair_weight[k];
      weights(j, i) += pair_weight[k];
    }
  }
  result.seconds_matching = Since(t0);
  const auto geometric_of = [&](int parent, int child) {
    std::vector<GeometricMatch> out;
    const int a = std::min(parent, child), b = std::max(parent, child);
    const auto it = geometric_matches.find({a, b});
    if (it != geometric_matches.end()) {
      out = it->second;
    } else if (UsesGeometric(options.features)) {  // a pair left out of the candidates: matched now
      out = MatchGeometric(prepared[a].geometric, prepared[b].geometric);
    }
    if (parent > child)
      for (GeometricMatch& g : out) std::swap(g.parent, g.child);
    return out;
  };
  // The SIFT matches of a pair both ways; a pair left out of the candidates (the driver tries it by
  // position) is matched when asked for.
  const auto sift_of = [&](int parent, int child) {
    if (table->confusion(parent, child) != kSkippedPair) return BothWays(*table, parent, child);
    Expected<MatchTable> one = MatchPairs({features[parent], features[child]}, {{0, 1}}, options.match, null_progress, cancel);
    return one ? BothWays(*one, 0, 1) : std::vector<FeatureMatch>();
  };

  LinkSource source;
  source.weights = weights;
  std::atomic<int> from_jobs{0};
  source.register_pair = [&](int parent, int child) {
    if (exchange && exchange->results) {  // register --collect: the job's registration
      const auto it = exchange->results->find({parent, child});
      if (it != exchange->results->end()) {
        ++from_jobs;
        return it->second;
      }
    }
    return RegisterPair(prepared[parent], prepared[child], sift_of(parent, child), geometric_of(parent, child),
                        options, cancel);
  };
  source.violation_rate = [&](int parent, int child, const Eigen::Isometry3d& parent_from_child) {
    return EvaluateAlignment(prepared[parent], prepared[child], parent_from_child, options.overlap_distance_m)
        .ViolationRate();
  };
  // The pairs overlapping at the registered poses (whether matched or not) become links of the global
  // step, refined from those poses: bounding spheres first, then SampleOverlap on the voxel samples
  // within 3 overlap distances (the samples are a voxel of one overlap distance apart). One parent at
  // a time: its k-d tree is built, used for every near child, and dropped (not all n at once).
  const double reach = 3.0 * options.overlap_distance_m;
  source.overlap_at = [&](const std::vector<Eigen::Isometry3d>& world, const std::vector<bool>& placed) {
    Eigen::MatrixXd overlap = Eigen::MatrixXd::Zero(n, n);
    std::vector<double> radius(n, 0.0);
    for (int i = 0; i < n; ++i)
      for (const Eigen::Vector3f& p : prepared[i].samples) radius[i] = std::max(radius[i], double(p.norm()));
    const auto near = [&](int i, int j) {
      return i != j && placed[i] && placed[j] &&
             (world[i].translation() - world[j].translation()).norm() < radius[i] + radius[j];
    };
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < n; ++i) {
      bool any = false;
      for (int j = 0; j < n && !any; ++j) any = near(i, j);
      if (!any) continue;
      const PointIndex index(ToDouble(prepared[i].samples));
      for (int j = 0; j < n; ++j)
        if (near(i, j)) overlap(i, j) = SampleOverlap(index, prepared[j].samples, world[i].inverse() * world[j], reach);
    }
    return overlap;
  };
  source.refine_pair = [&](int parent, int child, const Eigen::Isometry3d& parent_from_child) {
    PairResult r;
    r.link = RefinePair(prepared[parent], prepared[child], parent_from_child, options, options.overlap_distance_m, cancel);
    return r;
  };
  source.extra_overlap = options.thresholds.weak_overlap;  // as RegisterFromCurrentPoses
  source.extra_per_scan = options.global_partners;
  source.min_check_weight = options.min_check_matches;
  source.position_partners = 3;
  source.clusters = true;
  source.no_link_reason = "no link to a registered scan: no overlapping scan with enough feature matches";
  SubProgress pair_progress(progress, 0.5, 1.0);
  if (Status s = DriveRegistration(scans, *choices, source, options, pair_progress, cancel, &result); !s) {
    return s.error();
  }
  result.pairs_from_jobs = from_jobs;
  result.seconds_total = Since(t_start);
  progress.Report(1.0, "registration done");
  return result;
}

void ApplyRegistration(const ProjectRegistration& result, io::Project& project) {
  for (std::size_t i = 0; i < project.scans.size() && i < result.scans.size(); ++i) {
    io::ProjectScan& ps = project.scans[i];
    ps.registered = result.scans[i].registered;
    if (ps.registered) {
      ps.world_from_scan = result.scans[i].world_from_scan;
      ps.manual_pose = false;
    }
    ps.unregistered_reason = ps.registered ? "" : result.scans[i].reason;
    ps.unverified = !ps.registered && result.scans[i].unverified;
    ps.cluster.clear();
    if (!ps.registered && result.scans[i].cluster >= 0) {  // placed in its cluster's frame
      const int root = result.scans[i].cluster;
      ps.cluster = result.scans[root].name;
      ps.world_from_scan = project.scans[root].world_from_scan * result.scans[i].cluster_from_scan;
    }
    ps.coarse_world_from_scan.reset();
    if (ps.registered && result.scans[i].has_coarse) ps.coarse_world_from_scan = result.scans[i].coarse_world_from_scan;
  }
  for (std::size_t i = 0; i < project.scans.size() && i < result.scans.size(); ++i) {
    io::ProjectScan& ps = project.scans[i];
    const ScanRegistration& s = result.scans[i];
    auto measured = [](double v) { return v >= 0 ? std::optional<double>(v) : std::nullopt; };
    ps.start_consistency_m = measured(s.start_consistency_m);
    ps.consistency_m = measured(s.consistency_m);
    ps.conditioning = measured(s.conditioning);
  }
  project.consistency = result.consistency;
  project.confusion = result.confusion;
  project.confusion_scans.clear();
  for (const io::ProjectScan& s : project.scans) project.confusion_scans.push_back(s.name);
  // Keep the user's accept / reject decisions on links that were recomputed.
  std::vector<io::LinkRecord> links = result.links;
  for (io::LinkRecord& l : links) {
    for (const io::LinkRecord& old : project.links) {
      if (old.parent == l.parent && old.child == l.child) {
        l.user_accepted = old.user_accepted;
        l.user_rejected = old.user_rejected;
      }
    }
  }
  for (const io::LinkRecord& old : project.links) {
    bool kept = false;
    for (const io::LinkRecord& l : links) kept |= old.parent == l.parent && old.child == l.child;
    if (!kept && old.user_rejected) links.push_back(old);
  }
  project.links = std::move(links);
  if (result.root >= 0) project.root = project.scans[result.root].name;
}

Expected<ProjectRegistration> RegisterProjectScans(io::Project& project, const std::vector<Scan>& scans,
                                                   RegisterOptions options, ProgressSink& progress,
                                                   const CancelToken& cancel, const PairExchange* exchange) {
  ScanStore store(scans);
  return RegisterProjectScans(project, store, options, progress, cancel, exchange);
}

Expected<ProjectRegistration> RegisterProjectScans(io::Project& project, ScanStore& scans, RegisterOptions options,
                                                   ProgressSink& progress, const CancelToken& cancel,
                                                   const PairExchange* exchange) {
  const std::size_t n = project.scans.size();
  // The scans this run may place (options.only_scans; default all); the others keep pose and links.
  std::vector<bool> in_scope(n, options.only_scans.empty());
  for (const std::string& name : options.only_scans) {
    const int i = project.FindScan(name);
    if (i < 0) return MakeError(ErrorCode::kInvalidArgument, "scan '" + name + "' is not in the project");
    in_scope[i] = true;
  }
  UserChoices user;
  for (const io::ProjectScan& s : project.scans) user.parent_override.push_back(s.parent_override);
  for (const io::LinkRecord& l : project.links) {
    if (l.user_rejected) user.rejected.emplace_back(l.parent, l.child);
    const int c = project.FindScan(l.child);
    if (c < 0 || l.status == io::LinkStatus::kFailed || l.user_rejected || l.loop_check) continue;
    // The user's links (accepted, picked), and outside the scope every tree link, are used as they are.
    if (l.user_accepted || (!in_scope[c] && project.scans[c].registered)) user.kept.push_back(l);
  }
  if (!options.root && project.root) options.root = project.root;
  std::vector<bool> anchor(n, false);
  int anchors = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const io::ProjectScan& s = project.scans[i];
    anchors += anchor[i] = s.registered && ((options.keep_imported && s.imported_pose) || !in_scope[i]);
  }
  if (anchors > 0) {  // the datum is a pose that stays: the root must be one
    const int root = options.root ? project.FindScan(*options.root) : -1;
    if (root < 0 || !anchor[root]) {
      const int first = static_cast<int>(std::find(anchor.begin(), anchor.end(), true) - anchor.begin());
      options.root = project.scans[first].name;
    }
  }
  Expected<ProjectRegistration> result = RegisterScans(scans, user, options, progress, cancel, exchange);
  if (!result) return result.error();
  if (exchange && exchange->planned) return result;  // planned only: nothing registered
  // The user's hand placements are decisions (issue 14): kept as placed, and the scans registered
  // through one are placed from it (they rest on it), like scans below an imported pose.
  std::vector<bool> locked = anchor;
  int hand_placed = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (project.scans[i].registered && project.scans[i].manual_pose) locked[i] = true, ++hand_placed;
  if (anchors + hand_placed > 0) KeepImportedPoses(project, locked, &*result);
  const io::Project before = project;
  ApplyRegistration(*result, project);
  for (std::size_t i = 0; i < n; ++i) {
    io::ProjectScan& ps = project.scans[i];
    const io::ProjectScan& old = before.scans[i];
    if (!in_scope[i]) {  // outside the scope: as it was
      ps = old;
      continue;
    }
    if (locked[i] && old.manual_pose) {
      ps.manual_pose = true;
      LogInfo("scan '" + ps.name + "' keeps its hand placement (Release hand placement lets the registration place it)");
    }
    if (ps.registered && !anchor[i]) ps.imported_pose = false;    // re-estimated
    if (!ps.registered && old.registered && old.imported_pose) {  // the file's pose is not thrown away
      LogWarning("scan '" + ps.name + "' could not be registered (" + ps.unregistered_reason +
                 "); it keeps its imported pose");
      ps.registered = ps.imported_pose = true;
      ps.unverified = false;  // the report says the registration could not verify the file's pose
      ps.world_from_scan = old.world_from_scan;
      ps.cluster.clear();
    }
  }
  if (!options.only_scans.empty()) {  // links: the old ones of the scans outside the scope, the new ones inside
    std::vector<io::LinkRecord> links;
    for (const io::LinkRecord& l : before.links) {
      const int c = project.FindScan(l.child);
      if (c >= 0 && !in_scope[c]) links.push_back(l);
    }
    for (const io::LinkRecord& l : project.links) {
      const int c = project.FindScan(l.child);
      if (c >= 0 && in_scope[c]) links.push_back(l);
    }
    project.links = std::move(links);
    project.root = before.root ? before.root : project.root;
  }
  project.georef.reset();  // the poses moved: the last adjustment no longer describes them
  if (!project.control.empty()) {
    auto placed = GeoreferenceProject(project, scans, options, progress, cancel);
    if (placed) {
      result->georeferenced = true;
    } else if (placed.error().code == ErrorCode::kCancelled) {
      return placed.error();
    } else {
      result->georef_error = placed.error().message;
      LogWarning(placed.error().message + "; the registration stays in the root scan's frame");
    }
  }
  return result;
}

void KeepImportedPoses(const io::Project& project, const std::vector<bool>& anchor, ProjectRegistration* result) {
  std::vector<Eigen::Isometry3d> estimated;
  for (const ScanRegistration& s : result->scans) estimated.push_back(s.world_from_scan);
  for (std::size_t i = 0; i < result->scans.size(); ++i) {
    ScanRegistration& s = result->scans[i];
    if (anchor[i]) {
      s.world_from_scan = project.scans[i].world_from_scan;
      s.registered = true;
      s.reason.clear();
      continue;
    }
    if (!s.registered) continue;
    int a = s.parent;
    for (int steps = 0; a >= 0 && !anchor[a] && steps < static_cast<int>(anchor.size()); ++steps)
      a = result->scans[a].parent;
    if (a < 0 || !anchor[a]) continue;  // the root is an anchor, so only a broken tree gets here
    s.world_from_scan = project.scans[a].world_from_scan * estimated[a].inverse() * estimated[i];
  }
}

std::vector<ReferenceError> ReferenceErrors(const ProjectRegistration& result, const std::vector<Scan>& scans) {
  std::vector<ReferenceError> errors(scans.size());
  if (result.root < 0 || !scans[result.root].reference_world_from_scan) return errors;
  const Eigen::Isometry3d ref_root = *scans[result.root].reference_world_from_scan;
  const ScanRegistration& root = result.scans[result.root];
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const ScanRegistration& s = result.scans[i];
    if (!s.registered || !scans[i].reference_world_from_scan) continue;
    const Eigen::Isometry3d ref = ref_root.inverse() * *scans[i].reference_world_from_scan;
    const PoseError fine = ComparePoses(root.world_from_scan.inverse() * s.world_from_scan, ref);
    errors[i].available = true;
    errors[i].position_m = fine.position_m;
    errors[i].angle_rad = fine.angle_rad;
    if (s.has_coarse) {
      const PoseError coarse = ComparePoses(root.coarse_world_from_scan.inverse() * s.coarse_world_from_scan, ref);
      errors[i].has_coarse = true;
      errors[i].coarse_position_m = coarse.position_m;
      errors[i].coarse_angle_rad = coarse.angle_rad;
    }
  }
  return errors;
}

std::optional<PoseError> LinkReferenceError(const io::LinkRecord& link, const std::vector<Scan>& scans) {
  const Scan* parent = nullptr;
  const Scan* child = nullptr;
  for (const Scan& s : scans) {
    if (s.name == link.parent) parent = &s;
    if (s.name == link.child) child = &s;
  }
  if (!parent || !child || !parent->reference_world_from_scan || !child->reference_world_from_scan) return std::nullopt;
  return ComparePoses(link.parent_from_child,
                      parent->reference_world_from_scan->inverse() * *child->reference_world_from_scan);
}

std::vector<ReferenceError> ReferenceErrors(const io::Project& project) {
  // The saved result as the registration returned it; the scans need only their reference poses.
  ProjectRegistration result;
  result.root = project.root ? project.FindScan(*project.root) : -1;
  std::vector<Scan> scans(project.scans.size());
  for (std::size_t i = 0; i < project.scans.size(); ++i) {
    const io::ProjectScan& ps = project.scans[i];
    scans[i].name = ps.name;
    scans[i].reference_world_from_scan = ps.reference_world_from_scan;
    ScanRegistration s;
    s.name = ps.name;
    s.registered = ps.registered;
    s.world_from_scan = ps.world_from_scan;
    s.has_coarse = ps.coarse_world_from_scan.has_value() || static_cast<int>(i) == result.root;
    s.coarse_world_from_scan = ps.coarse_world_from_scan.value_or(ps.world_from_scan);
    result.scans.push_back(s);
  }
  if (result.root < 0 || !project.scans[result.root].registered) return std::vector<ReferenceError>(scans.size());
  return ReferenceErrors(result, scans);
}

}  // namespace scanreg::pipeline
