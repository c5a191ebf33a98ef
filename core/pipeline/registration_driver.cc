#include "core/pipeline/registration_driver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>

#include "core/common/log.h"
#include "core/geometry/transform.h"
#include "core/pipeline/global_registration.h"
#include "core/registration/scan_order.h"

namespace scanreg::pipeline {
namespace {

bool Contains(const std::vector<std::pair<int, int>>& edges, int parent, int child) {
  return std::find(edges.begin(), edges.end(), std::make_pair(parent, child)) != edges.end();
}

Error Cancelled() { return MakeError(ErrorCode::kCancelled, "registration cancelled"); }

// The scans came with poses of their own (from their files or placed by hand) when no two share one;
// projects read without poses have every scan at the identity.
bool HavePriorPoses(const std::vector<Scan>& scans) {
  for (std::size_t i = 0; i < scans.size(); ++i)
    for (std::size_t j = i + 1; j < scans.size(); ++j)
      if (scans[i].world_from_scan.isApprox(scans[j].world_from_scan, 1e-9)) return false;
  return scans.size() > 1;
}

// Partners by position (issue 11 item 4): the placed scans nearest to where an unplaced scan
// probably stands — its own prior pose when the scans have priors, else beside its neighbours in
// capture order (stations are set up one after the other) — nearest first, at most max_count.
std::vector<int> PositionPartners(int x, const std::vector<Scan>& scans, const std::vector<bool>& placed,
                                  const std::vector<Eigen::Isometry3d>& world, bool priors, int max_count) {
  const int n = static_cast<int>(scans.size());
  std::vector<Eigen::Vector3d> anchors;
  if (priors) anchors.push_back(scans[x].world_from_scan.translation());
  for (int q : {x - 1, x + 1})
    if (q >= 0 && q < n && placed[q]) anchors.push_back(world[q].translation());
  std::vector<std::pair<double, int>> by_distance;
  for (int p = 0; p < n; ++p) {
    if (!placed[p] || anchors.empty()) continue;
    double d = INFINITY;
    for (const Eigen::Vector3d& a : anchors) d = std::min(d, (world[p].translation() - a).norm());
    by_distance.emplace_back(d, p);
  }
  std::sort(by_distance.begin(), by_distance.end());
  std::vector<int> out;
  for (const auto& [d, p] : by_distance)
    if (static_cast<int>(out.size()) < max_count) out.push_back(p);
  return out;
}

}  // namespace

Status DriveRegistration(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                         const RegisterOptions& options, ProgressSink& progress, const CancelToken& cancel,
                         ProjectRegistration* result) {
  const int n = static_cast<int>(scans.size());
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<std::pair<int, int>> excluded = choices.excluded;

  // Each ordered pair is registered at most once. Pairs the tree or its checks will ask for next are
  // registered ahead, concurrently (issue 13, item 4), and wait in `ahead` until the walk reaches
  // them: the walk, and so the result, is the same whatever the thread count.
  std::map<std::pair<int, int>, PairResult> done, ahead;
  auto register_ahead = [&](const std::vector<std::pair<int, int>>& wanted) {
    std::vector<std::pair<int, int>> todo;
    for (const auto& e : wanted)
      if (!done.count(e) && !ahead.count(e) && !choices.kept.count(e) &&
          std::find(todo.begin(), todo.end(), e) == todo.end())
        todo.push_back(e);
    if (todo.size() < 2 || cancel.IsCancelled()) return;  // nothing to share between threads
    progress.Report(std::min(1.0, double(done.size()) / (2.0 * std::max(1, n - 1))),
                    std::string(source.verb) + " " + std::to_string(todo.size()) + " pairs");
    std::vector<PairResult> results(todo.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (long k = 0; k < static_cast<long>(todo.size()); ++k)
      if (!cancel.IsCancelled()) results[k] = source.register_pair(todo[k].first, todo[k].second);
    if (cancel.IsCancelled()) return;
    for (std::size_t k = 0; k < todo.size(); ++k) ahead.emplace(todo[k], std::move(results[k]));
  };
  auto link = [&](int parent, int child) -> PairResult& {
    auto it = done.find({parent, child});
    if (it != done.end()) return it->second;
    progress.Report(std::min(1.0, double(done.size()) / (2.0 * std::max(1, n - 1))),
                    std::string(source.verb) + " " + scans[child].name + " to " + scans[parent].name);
    const auto kept = choices.kept.find({parent, child});
    PairResult computed;
    if (kept != choices.kept.end()) {
      computed.link = kept->second;
    } else if (auto a = ahead.find({parent, child}); a != ahead.end()) {
      computed = std::move(a->second);
      ahead.erase(a);
    } else {
      computed = source.register_pair(parent, child);
    }
    PairResult& r = done.emplace(std::make_pair(parent, child), std::move(computed)).first->second;
    if (kept != choices.kept.end()) LogInfo(scans[child].name + " keeps its link to " + scans[parent].name + " (the user's)");
    LogInfo(scans[child].name + " -> " + scans[parent].name + ": " + io::LinkStatusName(r.link.status) +
            (r.link.reason.empty() ? "" : " (" + r.link.reason + ")"));
    return r;
  };
  auto fail_link = [&](int parent, int child, const std::string& reason) {
    PairResult& r = done.at({parent, child});
    r.link.status = io::LinkStatus::kFailed;
    r.link.reason = reason;
    excluded.emplace_back(parent, child);
  };

  // W §2 step 4 with failure handling: register along the tree; a failed link is excluded and the
  // tree recomputed, so the next-best edge takes its place.
  ScanOrder order;
  std::vector<Eigen::Isometry3d> world(n, Eigen::Isometry3d::Identity());
  std::vector<int> checked_with(n, -1);
  Eigen::MatrixXi weights = source.weights;
  const bool priors = HavePriorPoses(scans);
  std::vector<bool> position_tried(n, false);
  // Once the tree has settled, each scan it leaves out gets its partners by position as edges of the
  // lowest weights (they join only scans no link with matches placed); false when none is new.
  auto add_position_partners = [&]() {
    if (source.position_partners <= 0) return false;
    std::vector<bool> placed(n, false);
    for (int i = 0; i < n; ++i) placed[i] = i == order.root || order.parent[i] >= 0;
    bool added = false;
    for (int x = 0; x < n; ++x) {
      if (placed[x] || position_tried[x] || choices.overrides[x]) continue;
      position_tried[x] = true;
      const std::vector<int> partners = PositionPartners(x, scans, placed, world, priors, source.position_partners);
      for (std::size_t rank = 0; rank < partners.size(); ++rank) {
        const int p = partners[rank];
        if (Contains(excluded, p, x) || done.count({p, x}) || weights(p, x) >= source.min_weight) continue;
        weights(p, x) = source.min_weight + static_cast<int>(partners.size() - 1 - rank);  // nearest first
        LogInfo(scans[x].name + ": no link by matches; trying " + scans[p].name + " by position");
        added = true;
      }
    }
    return added;
  };
  for (int round = 0; round < 4 * n * n; ++round) {
    Expected<ScanOrder> o = ComputeScanOrder(weights, choices.root, choices.overrides, excluded, source.min_weight);
    if (!o) return o.error();
    order = *o;
    std::vector<std::pair<int, int>> tree_edges;
    for (int child : order.order)
      if (order.parent[child] >= 0) tree_edges.emplace_back(order.parent[child], child);
    register_ahead(tree_edges);
    bool changed = false;
    for (int child : order.order) {
      const int parent = order.parent[child];
      if (parent < 0) continue;
      if (cancel.IsCancelled()) return Cancelled();
      if (link(parent, child).link.status == io::LinkStatus::kFailed) {
        excluded.emplace_back(parent, child);
        changed = true;
        break;
      }
      world[child] = world[parent] * done.at({parent, child}).link.parent_from_child;
    }
    if (cancel.IsCancelled()) return Cancelled();
    if (changed) continue;
    if (!source.loop_checks || !options.verify_loops) {
      if (add_position_partners()) continue;
      break;
    }
    // Loop check (beyond W): register each scan also to its best other placed neighbour and compare
    // with the tree. Both links of a cycle that does not close are failed: a pairwise registration
    // can be self-consistent and wrong (repeated façades), a closed loop rarely is.
    // The links to check and, for each, its check partners best first: the best one only, or every
    // one until a loop closes when the link needs one.
    const bool check_all = options.verify_all_links || options.global;  // the graph needs the extra links
    auto check_partners = [&](int child) {
      std::vector<std::pair<int, int>> partners;  // (-weight, scan)
      const int parent = order.parent[child];
      if (parent < 0 || choices.kept.count({parent, child})) return partners;  // the user's link: never failed by a check
      const bool needs_loop = done.at({parent, child}).needs_loop;
      if (!check_all && !needs_loop && done.at({parent, child}).link.status == io::LinkStatus::kOk) return partners;
      // A loop that confirms a link leaves the child's subtree: a scan placed through the child
      // closes a loop of the subtree's own links, whatever the link to the parent is.
      auto below_child = [&](int q) {
        for (int a = q; a >= 0; a = order.parent[a])
          if (a == child) return true;
        return false;
      };
      for (int q : order.order) {
        if (q == child || q == parent || order.parent[q] == child || (needs_loop && below_child(q))) continue;
        if (Contains(excluded, q, child)) continue;
        const int w = std::max(weights(q, child), weights(child, q));
        if (w >= source.min_check_weight) partners.emplace_back(-w, q);
      }
      std::stable_sort(partners.begin(), partners.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      if (!needs_loop && partners.size() > 1) partners.resize(1);
      return partners;
    };
    std::vector<std::pair<int, int>> first_checks;  // each link's first check, unless the reverse serves
    for (int child : order.order) {
      const std::vector<std::pair<int, int>> partners = check_partners(child);
      if (partners.empty()) continue;
      const auto reverse = done.find({child, partners.front().second});
      if (reverse == done.end() || reverse->second.link.status == io::LinkStatus::kFailed)
        first_checks.emplace_back(partners.front().second, child);
    }
    register_ahead(first_checks);
    // The links that need a loop are checked first: a wrong one (a plan-view pose on a parallel
    // street) fails its own check, before the loops of sound links through the scans it misplaced
    // open and fail those links instead.
    std::vector<int> check_order;
    for (int pass = 0; pass < 2; ++pass)
      for (int child : order.order)
        if (order.parent[child] >= 0 && done.at({order.parent[child], child}).needs_loop == (pass == 0))
          check_order.push_back(child);
    for (int child : check_order) {
      const int parent = order.parent[child];
      if (choices.kept.count({parent, child})) continue;  // the user's link: never failed by a check
      const bool needs_loop = done.at({parent, child}).needs_loop;
      if (!check_all && !needs_loop && done.at({parent, child}).link.status == io::LinkStatus::kOk) continue;
      const std::vector<std::pair<int, int>> partners = check_partners(child);
      bool closed = false, open = false;
      for (const auto& [neg_weight, best] : partners) {
        // A check already made the other way round serves (inverted).
        const auto reverse = done.find({child, best});
        const bool use_reverse = reverse != done.end() && reverse->second.link.status != io::LinkStatus::kFailed;
        const PairResult& check = use_reverse ? reverse->second : link(best, child);
        if (check.link.status == io::LinkStatus::kFailed) continue;
        const Eigen::Isometry3d best_from_child =
            use_reverse ? check.link.parent_from_child.inverse() : check.link.parent_from_child;
        if (!use_reverse) checked_with[child] = best;
        const PoseError gap = ComparePoses(world[best] * best_from_child, world[child]);
        if (gap.position_m <= options.loop_tolerance_m && gap.angle_rad <= options.loop_tolerance_rad) {
          // A check that itself needs a loop does not confirm one: two plan-view poses from
          // neighbouring scans agree on the same wrong street as readily as on the right one.
          if (needs_loop && check.needs_loop) continue;
          closed = true;
          break;
        }
        char buf[200];
        std::snprintf(buf, sizeof buf, "loop %s-%s-%s does not close: %.3f m / %.2f° apart", scans[parent].name.c_str(),
                      scans[child].name.c_str(), scans[best].name.c_str(), gap.position_m, gap.angle_rad * 180 / M_PI);
        // Both links are failed — unless only the link checked needs a loop: then it is the suspect,
        // and the sound check stays (it may place the child once the suspect is gone).
        const bool only_suspect = needs_loop && !check.needs_loop;
        LogWarning(std::string(buf) + (only_suspect ? "; the link that needed a loop failed" : "; both links failed"));
        fail_link(parent, child, buf);
        if (!only_suspect) fail_link(use_reverse ? child : best, use_reverse ? best : child, buf);
        open = true;
        break;
      }
      if (!closed && !open && needs_loop) {
        const std::string& why = done.at({parent, child}).link.reason;
        fail_link(parent, child, why.substr(0, why.find("; a loop")) + "; no loop through another scan confirms it");
        open = true;
      }
      if (open) {
        changed = true;
        break;
      }
    }
    if (!changed && !add_position_partners()) break;
  }

  // Clusters among the scans left out: each grows from the heaviest edge between them.
  std::vector<int> cluster_of(n, -1), cluster_parent(n, -1);
  std::vector<Eigen::Isometry3d> cluster_pose(n, Eigen::Isometry3d::Identity());
  if (source.clusters) {
    std::vector<bool> free(n, false);
    for (int i = 0; i < n; ++i) free[i] = i != order.root && order.parent[i] < 0;
    for (int round = 0; round < n; ++round) {
      int best = source.min_weight - 1, croot = -1;
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
          if (i != j && free[i] && free[j] && weights(i, j) > best && !Contains(excluded, i, j)) best = weights(i, j), croot = i;
      if (croot < 0) break;
      Eigen::MatrixXi w = Eigen::MatrixXi::Zero(n, n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
          if (free[i] && free[j]) w(i, j) = weights(i, j);
      ScanOrder co;
      for (int attempt = 0; attempt < n * n; ++attempt) {
        Expected<ScanOrder> o = ComputeScanOrder(w, croot, {}, excluded, source.min_weight);
        if (!o) return o.error();
        co = *o;
        bool changed = false;
        for (int child : co.order) {
          const int parent = co.parent[child];
          if (parent < 0) continue;
          if (cancel.IsCancelled()) return Cancelled();
          if (link(parent, child).link.status == io::LinkStatus::kFailed) {
            excluded.emplace_back(parent, child);
            changed = true;
            break;
          }
          cluster_pose[child] = cluster_pose[parent] * done.at({parent, child}).link.parent_from_child;
        }
        if (!changed) break;
      }
      free[croot] = false;
      if (co.order.size() < 2) continue;  // its edges all failed: no cluster
      for (int child : co.order) {
        cluster_of[child] = croot;
        cluster_parent[child] = co.parent[child];
        free[child] = false;
      }
      LogInfo("scans registered to each other but not to the root: a cluster of " + std::to_string(co.order.size()) +
              " around " + scans[croot].name);
    }
  }

  // Chain world poses from the root, which keeps its current pose (W §2 step 10).
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
    const PairResult& pr = done.at({parent, child});
    ScanRegistration& s = result->scans[child];
    const ScanRegistration& p = result->scans[parent];
    s.registered = true;
    s.reason.clear();
    s.parent = parent;
    s.world_from_scan = p.world_from_scan * pr.link.parent_from_child;
    s.has_coarse = p.has_coarse && pr.coarse_ok;
    if (s.has_coarse) s.coarse_world_from_scan = p.coarse_world_from_scan * pr.coarse_parent_from_child;
    result->links.push_back(pr.link);
  }
  for (int i = 0; i < n; ++i) {
    if (cluster_of[i] < 0 || result->scans[i].registered) continue;
    result->scans[i].cluster = cluster_of[i];
    result->scans[i].cluster_from_scan = cluster_pose[i];
    if (cluster_parent[i] >= 0) result->links.push_back(done.at({cluster_parent[i], i}).link);
  }
  // Loop-check links that closed (evidence, not chained).
  for (int child = 0; child < n; ++child) {
    if (checked_with[child] < 0 || !result->scans[child].registered) continue;
    const auto it = done.find({checked_with[child], child});
    if (it == done.end() || it->second.link.status == io::LinkStatus::kFailed) continue;
    if (order.parent[child] == checked_with[child]) continue;
    io::LinkRecord l = it->second.link;
    l.loop_check = true;
    result->links.push_back(l);
  }
  if (options.global) {
    // Every other overlapping pair becomes a link of the pose graph (once: a loop check may hold it).
    auto linked = [&](int i, int j) {
      for (const io::LinkRecord& l : result->links)
        if ((l.parent == scans[i].name && l.child == scans[j].name) ||
            (l.parent == scans[j].name && l.child == scans[i].name))
          return true;
      return false;
    };
    const bool at_poses = source.overlap.size() == 0 && source.overlap_at && source.refine_pair;
    Eigen::MatrixXd overlap = source.overlap;
    std::vector<bool> placed(n);
    std::vector<Eigen::Isometry3d> placed_world(n);
    for (int i = 0; i < n; ++i) {
      placed[i] = result->scans[i].registered;
      placed_world[i] = result->scans[i].world_from_scan;
    }
    if (at_poses) overlap = source.overlap_at(placed_world, placed);
    std::vector<std::pair<int, int>> extra;  // (parent, child): the larger overlap's scan is the parent
    for (int i = 0; i < overlap.rows(); ++i)
      for (int j = i + 1; j < overlap.cols(); ++j) {
        if (order.parent[j] == i || order.parent[i] == j || linked(i, j)) continue;
        if (!placed[i] || !placed[j]) continue;
        if (std::max(overlap(i, j), overlap(j, i)) < source.extra_overlap) continue;
        if (Contains(excluded, i, j)) continue;
        extra.push_back(overlap(i, j) >= overlap(j, i) ? std::make_pair(i, j) : std::make_pair(j, i));
      }
    if (source.extra_per_scan > 0) {  // each scan's largest overlaps; the graph needs a few, not all
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
      extra = std::move(kept);
    }
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
      io::LinkRecord l = at_poses ? refined[k].link : link(extra[k].first, extra[k].second).link;
      if (l.status == io::LinkStatus::kFailed) continue;
      l.loop_check = true;
      result->links.push_back(l);
    }
    if (Status g = RunGlobalRegistration(scans, cancel, result); !g) return g;
    // The user's links hold exactly: the graph may not bend them. Parents first, each kept child
    // and the scans under it move back onto its link.
    auto under = [&](int d, int top) {
      for (int steps = 0; d >= 0 && steps <= n; ++steps, d = order.parent[d])
        if (d == top) return true;
      return false;
    };
    for (int child : order.order) {
      const int parent = order.parent[child];
      const auto kept = choices.kept.find({parent, child});
      if (parent < 0 || kept == choices.kept.end()) continue;
      const Eigen::Isometry3d delta = result->scans[parent].world_from_scan * kept->second.parent_from_child *
                                      result->scans[child].world_from_scan.inverse();
      for (int d = 0; d < n; ++d)
        if (result->scans[d].registered && under(d, child))
          result->scans[d].world_from_scan = delta * result->scans[d].world_from_scan;
    }
  }
  // Failed attempts, and the reason of each scan left out.
  for (const auto& [key, pr] : done) {
    if (pr.link.status != io::LinkStatus::kFailed) continue;
    result->links.push_back(pr.link);
    ScanRegistration& s = result->scans[key.second];
    if (!s.registered) s.reason = "link to " + scans[key.first].name + " failed: " + pr.link.reason;
  }
  for (int i = 0; i < n; ++i) {
    const std::optional<int>& parent = choices.overrides[i];
    if (!parent || result->scans[i].registered) continue;
    auto it = done.find({*parent, i});
    result->scans[i].reason = it != done.end()
                                  ? "the link to its parent override " + scans[*parent].name + " failed (" +
                                        it->second.link.reason + "); remove or change the override"
                                  : "its parent override " + scans[*parent].name + " is not registered";
  }
  result->seconds_pairs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return Status::Ok();
}

}  // namespace scanreg::pipeline
