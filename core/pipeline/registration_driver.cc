#include "core/pipeline/registration_driver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "core/common/log.h"
#include "core/pipeline/global_registration.h"
#include "core/pipeline/pair_book.h"
#include "core/pipeline/tree_walk.h"
#include "core/registration/scan_order.h"

namespace scanreg::pipeline {
namespace {

Error Cancelled() { return MakeError(ErrorCode::kCancelled, "registration cancelled"); }

// The scans the tree leaves out, registered to each other along trees of their own.
struct Clusters {
  std::vector<int> of, parent;  // per scan: the cluster's root scan and the parent in it, or -1
  std::vector<Eigen::Isometry3d> pose;  // cluster_from_scan
};

// Clusters among the scans left out: each grows from the heaviest edge between them.
Expected<Clusters> GrowClusters(const std::vector<Scan>& scans, const TreeWalk& walk, const LinkSource& source,
                                const CancelToken& cancel, PairBook& book) {
  const int n = static_cast<int>(scans.size());
  const Eigen::MatrixXi& weights = walk.weights;
  Clusters c{std::vector<int>(n, -1), std::vector<int>(n, -1),
             std::vector<Eigen::Isometry3d>(n, Eigen::Isometry3d::Identity())};
  if (!source.clusters) return c;
  std::vector<bool> free(n, false);
  for (int i = 0; i < n; ++i) free[i] = i != walk.order.root && walk.order.parent[i] < 0;
  for (int round = 0; round < n; ++round) {
    int best = source.min_weight - 1, croot = -1;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (i != j && free[i] && free[j] && weights(i, j) > best && !book.Excluded(i, j)) best = weights(i, j), croot = i;
    if (croot < 0) break;
    Eigen::MatrixXi w = Eigen::MatrixXi::Zero(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (free[i] && free[j]) w(i, j) = weights(i, j);
    ScanOrder co;
    for (int attempt = 0; attempt < n * n; ++attempt) {
      Expected<ScanOrder> o = ComputeScanOrder(w, croot, {}, book.excluded(), source.min_weight);
      if (!o) return o.error();
      co = *o;
      bool changed = false;
      for (int child : co.order) {
        const int parent = co.parent[child];
        if (parent < 0) continue;
        if (cancel.IsCancelled()) return Cancelled();
        const PairResult& link = book.Link(parent, child);
        if (link.link.status == io::LinkStatus::kFailed) {
          book.Exclude(parent, child);
          changed = true;
          break;
        }
        // No loop is checked within a cluster: a link that needs one fails, as outside the settled
        // tree (TreeWalk's FailUnconfirmed; measured: two rooms of an office floor joined by a
        // plan-view pose 6.6 m and 90° off, listed as weak).
        if (link.needs_loop) {
          const std::string why = link.link.reason;
          book.Fail(parent, child, why.substr(0, why.find("; a loop")) + "; not used: no loop confirms it");
          changed = true;
          break;
        }
        c.pose[child] = c.pose[parent] * book.At(parent, child).link.parent_from_child;
      }
      if (!changed) break;
    }
    free[croot] = false;
    if (co.order.size() < 2) continue;  // its edges all failed: no cluster
    for (int child : co.order) {
      c.of[child] = croot;
      c.parent[child] = co.parent[child];
      free[child] = false;
    }
    LogInfo("scans registered to each other but not to the root: a cluster of " + std::to_string(co.order.size()) +
            " around " + scans[croot].name);
  }
  return c;
}

// Chains world poses from the root, which keeps its current pose (W §2 step 10); the links of the
// tree, of the clusters and the loop checks that closed (evidence, not chained) go into result.
void ChainPoses(const std::vector<Scan>& scans, const TreeWalk& walk, const Clusters& clusters, const LinkSource& source,
                PairBook& book, ProjectRegistration* result) {
  const int n = static_cast<int>(scans.size());
  const ScanOrder& order = walk.order;
  result->root = order.root;
  result->scans.assign(n, ScanRegistration());
  for (int i = 0; i < n; ++i) {
    result->scans[i].name = scans[i].name;
    result->scans[i].reason = source.no_link_reason;
  }
  ScanRegistration& r0 = result->scans[order.root];
  r0.registered = true;
  r0.reason.clear();
  r0.world_from_scan = scans[order.root].world_from_scan;
  if (source.has_coarse) {
    r0.coarse_world_from_scan = r0.world_from_scan;
    r0.has_coarse = true;
  }
  for (int child : order.order) {
    const int parent = order.parent[child];
    if (parent < 0) continue;
    const PairResult& pr = book.At(parent, child);
    ScanRegistration& s = result->scans[child];
    const ScanRegistration& p = result->scans[parent];
    s.registered = true;
    s.reason.clear();
    s.parent = parent;
    s.world_from_scan = p.world_from_scan * pr.link.parent_from_child;
    s.has_coarse = p.has_coarse && pr.coarse_ok;
    if (s.has_coarse) s.coarse_world_from_scan = p.coarse_world_from_scan * pr.coarse_parent_from_child;
    // Placed, but not verified (issue 33): by a weak link no loop confirms, or through a scan that
    // is not verified. It stays unregistered at its start pose, and its link stays listed (weak),
    // for the user to accept when the pose is right.
    const bool weak = walk.unconfirmed_weak[child];
    if (weak || p.unverified) {
      s.registered = false;
      s.unverified = true;
      s.parent = -1;
      s.world_from_scan = scans[child].world_from_scan;
      s.has_coarse = false;
      s.reason = weak ? "not verified: placed only by a weak link from " + scans[parent].name + " (" + pr.link.reason +
                            "); accept the link if its pose is right"
                      : "not verified: placed through " + scans[parent].name + ", which is not verified";
    }
    result->links.push_back(pr.link);
  }
  for (int i = 0; i < n; ++i) {
    if (clusters.of[i] < 0 || result->scans[i].registered) continue;
    result->scans[i].cluster = clusters.of[i];
    result->scans[i].cluster_from_scan = clusters.pose[i];
    if (clusters.parent[i] >= 0) result->links.push_back(book.At(clusters.parent[i], i).link);
  }
  for (int child = 0; child < n; ++child) {
    const int with = walk.checked_with[child];
    if (with < 0 || !result->scans[child].registered) continue;
    const PairResult* check = book.Find(with, child);
    if (!check || check->link.status == io::LinkStatus::kFailed) continue;
    if (order.parent[child] == with) continue;
    io::LinkRecord l = check->link;
    l.loop_check = true;
    result->links.push_back(l);
  }
}

// The other pairs overlapping by source.extra_overlap (each scan's largest with extra_per_scan), as
// (parent, child) with the larger overlap's scan the parent.
std::vector<std::pair<int, int>> ExtraPairs(const Eigen::MatrixXd& overlap, const std::vector<bool>& placed,
                                            const ScanOrder& order, const LinkSource& source, const PairBook& book,
                                            const ProjectRegistration& result, const std::vector<Scan>& scans) {
  const int n = static_cast<int>(scans.size());
  auto linked = [&](int i, int j) {  // once: a loop check may hold it
    for (const io::LinkRecord& l : result.links)
      if ((l.parent == scans[i].name && l.child == scans[j].name) ||
          (l.parent == scans[j].name && l.child == scans[i].name))
        return true;
    return false;
  };
  std::vector<std::pair<int, int>> extra;
  for (int i = 0; i < overlap.rows(); ++i)
    for (int j = i + 1; j < overlap.cols(); ++j) {
      if (order.parent[j] == i || order.parent[i] == j || linked(i, j)) continue;
      if (!placed[i] || !placed[j]) continue;
      if (std::max(overlap(i, j), overlap(j, i)) < source.extra_overlap) continue;
      if (book.Excluded(i, j)) continue;
      extra.push_back(overlap(i, j) >= overlap(j, i) ? std::make_pair(i, j) : std::make_pair(j, i));
    }
  if (source.extra_per_scan <= 0) return extra;
  // Each scan's largest overlaps: the graph needs a few, not all.
  auto larger = [&](const std::pair<int, int>& e) { return std::max(overlap(e.first, e.second), overlap(e.second, e.first)); };
  std::vector<std::vector<int>> of_scan(n);  // indices into extra
  for (std::size_t k = 0; k < extra.size(); ++k) {
    of_scan[extra[k].first].push_back(static_cast<int>(k));
    of_scan[extra[k].second].push_back(static_cast<int>(k));
  }
  std::vector<bool> keep(extra.size(), false);
  for (std::vector<int>& ks : of_scan) {
    std::stable_sort(ks.begin(), ks.end(), [&](int a, int b) { return larger(extra[a]) > larger(extra[b]); });
    for (std::size_t r = 0; r < ks.size() && r < static_cast<std::size_t>(source.extra_per_scan); ++r) keep[ks[r]] = true;
  }
  std::vector<std::pair<int, int>> kept;
  for (std::size_t k = 0; k < extra.size(); ++k)
    if (keep[k]) kept.push_back(extra[k]);
  if (kept.size() < extra.size())
    LogInfo("global step: " + std::to_string(kept.size()) + " of " + std::to_string(extra.size()) +
            " more overlapping pairs (each scan's " + std::to_string(source.extra_per_scan) + " largest overlaps)");
  return kept;
}

// The global step: every other overlapping pair becomes a link of the pose graph, the graph is
// solved, and the user's links are held exactly.
Status RunGlobalStep(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const TreeWalk& walk,
                     const LinkSource& source, ProgressSink& progress, const CancelToken& cancel, PairBook& book,
                     ProjectRegistration* result) {
  const int n = static_cast<int>(scans.size());
  const ScanOrder& order = walk.order;
  const bool at_poses = source.overlap.size() == 0 && source.overlap_at && source.refine_pair;
  Eigen::MatrixXd overlap = source.overlap;
  std::vector<bool> placed(n);
  std::vector<Eigen::Isometry3d> placed_world(n);
  for (int i = 0; i < n; ++i) {
    placed[i] = result->scans[i].registered;
    placed_world[i] = result->scans[i].world_from_scan;
  }
  if (at_poses) overlap = source.overlap_at(placed_world, placed);
  const std::vector<std::pair<int, int>> extra = ExtraPairs(overlap, placed, order, source, book, *result, scans);
  if (cancel.IsCancelled()) return Cancelled();
  std::vector<PairResult> refined(at_poses ? extra.size() : 0);
  if (at_poses) {  // independent refinements from the registered poses, concurrently
    progress.Report(1.0, "refining " + std::to_string(extra.size()) + " more overlapping pairs for the global step");
#pragma omp parallel for schedule(dynamic, 1)
    for (long k = 0; k < static_cast<long>(extra.size()); ++k) {
      if (cancel.IsCancelled()) continue;
      const auto [p, c] = extra[k];
      refined[k] = source.refine_pair(p, c, placed_world[p].inverse() * placed_world[c]);
    }
    if (cancel.IsCancelled()) return Cancelled();
    result->pairs_by_overlap = extra;
  }
  for (std::size_t k = 0; k < extra.size(); ++k) {
    if (cancel.IsCancelled()) return Cancelled();
    io::LinkRecord l = at_poses ? refined[k].link : book.Link(extra[k].first, extra[k].second).link;
    if (l.status == io::LinkStatus::kFailed) continue;
    l.loop_check = true;
    result->links.push_back(l);
  }
  if (Status g = RunGlobalRegistration(scans, cancel, result); !g) return g;
  HoldKeptLinks(choices, result);
  return Status::Ok();
}

// Failed attempts join the links, and each scan left out gets its reason (a scan placed but not
// verified keeps the reason that says so): its nearest miss, the failed link a loop could still
// confirm (failed only for want of one), else the one with the largest overlap — not whichever
// attempt came last (a busy street's station named a 36 m-off pose with 13 % conflict, not the
// neighbour's link that fitted with traffic in the way).
void ExplainLeftOut(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const PairBook& book,
                    ProjectRegistration* result) {
  std::vector<const PairResult*> nearest(scans.size(), nullptr);
  std::vector<int> nearest_parent(scans.size(), -1);
  auto nearer = [](const PairResult& a, const PairResult& b) {
    return a.unconfirmed != b.unconfirmed ? a.unconfirmed : a.link.overlap > b.link.overlap;
  };
  for (const auto& [key, pr] : book.done()) {
    if (pr.link.status != io::LinkStatus::kFailed) continue;
    result->links.push_back(pr.link);
    const int child = key.second;
    if (!nearest[child] || nearer(pr, *nearest[child])) nearest[child] = &pr, nearest_parent[child] = key.first;
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    ScanRegistration& s = result->scans[i];
    if (s.registered || s.unverified || !nearest[i]) continue;
    s.reason = "link to " + scans[nearest_parent[i]].name + " failed: " + nearest[i]->link.reason;
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const std::optional<int>& parent = choices.overrides[i];
    if (!parent || result->scans[i].registered) continue;
    const PairResult* link = book.Find(*parent, static_cast<int>(i));
    result->scans[i].reason = link ? "the link to its parent override " + scans[*parent].name + " failed (" +
                                         link->link.reason + "); remove or change the override"
                                   : "its parent override " + scans[*parent].name + " is not registered";
  }
}

}  // namespace

void HoldKeptLinks(const ScanOrderChoices& choices, ProjectRegistration* result) {
  const int n = static_cast<int>(result->scans.size());
  auto under = [&](int d, int top) {
    for (int steps = 0; d >= 0 && steps <= n; ++steps, d = result->scans[d].parent)
      if (d == top) return true;
    return false;
  };
  std::vector<int> order;  // parents first
  std::vector<bool> listed(n, false);
  for (int round = 0; round <= n; ++round)
    for (int i = 0; i < n; ++i) {
      const int p = result->scans[i].parent;
      if (!listed[i] && result->scans[i].registered && (p < 0 || listed[p])) listed[i] = true, order.push_back(i);
    }
  for (int child : order) {
    const int parent = result->scans[child].parent;
    const auto kept = choices.kept.find({parent, child});
    if (parent < 0 || kept == choices.kept.end()) continue;
    const Eigen::Isometry3d delta = result->scans[parent].world_from_scan * kept->second.parent_from_child *
                                    result->scans[child].world_from_scan.inverse();
    for (int d = 0; d < n; ++d)
      if (result->scans[d].registered && under(d, child))
        result->scans[d].world_from_scan = delta * result->scans[d].world_from_scan;
  }
}

Status DriveRegistration(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                         const RegisterOptions& options, ProgressSink& progress, const CancelToken& cancel,
                         ProjectRegistration* result) {
  const auto t0 = std::chrono::steady_clock::now();
  PairBook book(scans, choices, source, progress, cancel);
  Expected<TreeWalk> walk = WalkTree(scans, choices, source, options, cancel, book);
  if (!walk) return walk.error();
  Expected<Clusters> clusters = GrowClusters(scans, *walk, source, cancel, book);
  if (!clusters) return clusters.error();
  ChainPoses(scans, *walk, *clusters, source, book, result);
  if (options.global) {
    if (Status s = RunGlobalStep(scans, choices, *walk, source, progress, cancel, book, result); !s) return s;
  }
  ExplainLeftOut(scans, choices, book, result);
  result->seconds_pairs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return Status::Ok();
}

}  // namespace scanreg::pipeline
