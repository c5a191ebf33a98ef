#include "core/pipeline/tree_walk.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <tuple>

#include "core/common/log.h"
#include "core/geometry/transform.h"

namespace scanreg::pipeline {
namespace {

// Closing checks that need a loop themselves which together confirm a link that needs one: with
// the link, three scans put its child on one spot (CheckLink).
constexpr int kSuspectsThatConfirm = 2;

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

class Walker {
 public:
  Walker(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
         const RegisterOptions& options, const CancelToken& cancel, PairBook& book)
      : scans_(scans), choices_(choices), source_(source), options_(options), cancel_(cancel), book_(book),
        n_(static_cast<int>(scans.size())), priors_(HavePriorPoses(scans)), position_tried_(n_, false) {
    walk_.world.assign(n_, Eigen::Isometry3d::Identity());
    walk_.checked_with.assign(n_, -1);
    walk_.unconfirmed_weak.assign(n_, false);
    closed_.assign(n_, false);
    walk_.weights = source.weights;
  }

  Expected<TreeWalk> Run() {
    for (int round = 0; round < 4 * n_ * n_; ++round) {
      Expected<ScanOrder> o = ComputeScanOrder(walk_.weights, choices_.root, choices_.overrides, book_.excluded(),
                                               source_.min_weight);
      if (!o) return o.error();
      walk_.order = *o;
      const bool changed = PlaceAlongTree();
      if (cancel_.IsCancelled()) return Cancelled();
      if (changed) continue;
      if (!source_.loop_checks || !options_.verify_loops) {
        if (AddPositionPartners()) continue;
        break;
      }
      if (!CheckLoops() && !AddPositionPartners()) break;
      if (cancel_.IsCancelled()) return Cancelled();
    }
    FailUnconfirmed();
    MarkUnconfirmedWeak();
    return walk_;
  }

 private:
  const ScanOrder& order() const { return walk_.order; }

  // Registers the tree's links in placement order and chains the world poses; true when a link
  // failed (it is excluded: the tree must be recomputed).
  bool PlaceAlongTree() {
    std::vector<std::pair<int, int>> tree_edges;
    for (int child : order().order)
      if (order().parent[child] >= 0) tree_edges.emplace_back(order().parent[child], child);
    book_.RegisterAhead(tree_edges);
    for (int child : order().order) {
      const int parent = order().parent[child];
      if (parent < 0) continue;
      if (cancel_.IsCancelled()) return false;
      if (book_.Link(parent, child).link.status == io::LinkStatus::kFailed) {
        book_.Exclude(parent, child);
        return true;
      }
      walk_.world[child] = walk_.world[parent] * book_.At(parent, child).link.parent_from_child;
    }
    return false;
  }

  // Once the tree has settled, each scan it leaves out gets its partners by position as edges of the
  // lowest weights (they join only scans no link with matches placed); false when none is new.
  bool AddPositionPartners() {
    if (source_.position_partners <= 0) return false;
    std::vector<bool> placed(n_, false);
    for (int i = 0; i < n_; ++i) placed[i] = i == order().root || order().parent[i] >= 0;
    bool added = false;
    for (int x = 0; x < n_; ++x) {
      if (placed[x] || position_tried_[x] || choices_.overrides[x]) continue;
      position_tried_[x] = true;
      const std::vector<int> partners = PositionPartners(x, scans_, placed, walk_.world, priors_, source_.position_partners);
      for (std::size_t rank = 0; rank < partners.size(); ++rank) {
        const int p = partners[rank];
        if (book_.Excluded(p, x) || book_.Has(p, x) || walk_.weights(p, x) >= source_.min_weight) continue;
        walk_.weights(p, x) = source_.min_weight + static_cast<int>(partners.size() - 1 - rank);  // nearest first
        LogInfo(scans_[x].name + ": no link by matches; trying " + scans_[p].name + " by position");
        added = true;
      }
    }
    return added;
  }

  bool CheckAll() const { return options_.verify_all_links || options_.global; }  // the graph needs the extra links

  // The check partners of a tree link, best first: the best one only, or every one until a loop
  // closes when the link needs one. Empty when the link is not to be checked.
  std::vector<std::pair<int, int>> CheckPartners(int child) const {
    std::vector<std::pair<int, int>> partners;  // (-weight, scan)
    const int parent = order().parent[child];
    if (parent < 0 || choices_.kept.count({parent, child})) return partners;  // the user's link: never failed by a check
    const bool needs_loop = NeedsLoop(parent, child);
    if (!CheckAll() && !needs_loop && book_.At(parent, child).link.status == io::LinkStatus::kOk) return partners;
    // A link with weak support is confirmed only by a closed loop (issue 33: "registered" means
    // verified), so every partner is tried in turn until a check serves.
    const bool weak = WeakSupport(child);
    // A loop that confirms a link leaves the child's subtree: a scan placed through the child
    // closes a loop of the subtree's own links, whatever the link to the parent is.
    auto below_child = [&](int q) { return PlacedThrough(q, child); };
    for (int q : order().order) {
      if (q == child || q == parent || order().parent[q] == child || ((needs_loop || weak) && below_child(q))) continue;
      const PairResult* registered = book_.Find(q, child);  // the user's rejected links are excluded unregistered
      if (book_.Excluded(q, child) && !(registered && registered->unconfirmed)) continue;
      const int w = std::max(walk_.weights(q, child), walk_.weights(child, q));
      if (w >= source_.min_check_weight) partners.emplace_back(-w, q);
    }
    std::stable_sort(partners.begin(), partners.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    if (!needs_loop && !weak && partners.size() > 1) partners.resize(1);
    return partners;
  }

  // Loop check (beyond W): register each scan also to its best other placed neighbour and compare
  // with the tree. Both links of a cycle that does not close are failed: a pairwise registration
  // can be self-consistent and wrong (repeated façades), a closed loop rarely is. True when a link
  // failed (the tree must be recomputed).
  bool CheckLoops() {
    closed_.assign(n_, false);
    std::vector<std::pair<int, int>> first_checks;  // each link's first check, unless the reverse serves
    for (int child : order().order) {
      const std::vector<std::pair<int, int>> partners = CheckPartners(child);
      if (partners.empty()) continue;
      const PairResult* reverse = book_.Find(child, partners.front().second);
      if (!reverse || reverse->link.status == io::LinkStatus::kFailed)
        first_checks.emplace_back(partners.front().second, child);
    }
    book_.RegisterAhead(first_checks);
    // The links that need a loop are checked first: a wrong one (a plan-view pose on a parallel
    // street) fails its own check, before the loops of sound links through the scans it misplaced
    // open and fail those links instead.
    std::vector<int> check_order;
    for (int pass = 0; pass < 2; ++pass)
      for (int child : order().order)
        if (order().parent[child] >= 0 && NeedsLoop(order().parent[child], child) == (pass == 0))
          check_order.push_back(child);
    for (int child : check_order)
      if (CheckLink(child)) return true;
    return false;
  }

  // Checks the tree link of `child`; true when it (and maybe its check) failed.
  bool CheckLink(int child) {
    const int parent = order().parent[child];
    if (choices_.kept.count({parent, child})) return false;  // the user's link: never failed by a check
    const bool needs_loop = NeedsLoop(parent, child);
    if (!CheckAll() && !needs_loop && book_.At(parent, child).link.status == io::LinkStatus::kOk) return false;
    const std::vector<std::pair<int, int>> partners = CheckPartners(child);
    const std::vector<Eigen::Isometry3d>& world = walk_.world;
    int suspects_agreeing = 0;  // checks that close the loop but need a loop themselves
    for (const auto& [neg_weight, best] : partners) {
      // A check already made the other way round serves (inverted).
      // A check failed only for want of a loop (PairResult::unconfirmed) still serves, as one
      // that needs a loop itself.
      const auto serves = [](const PairResult& r) { return r.link.status != io::LinkStatus::kFailed || r.unconfirmed; };
      const PairResult* reverse = book_.Find(child, best);
      const bool use_reverse = reverse && serves(*reverse);
      const PairResult& check = use_reverse ? *reverse : book_.Link(best, child);
      if (!serves(check)) continue;
      const Eigen::Isometry3d best_from_child =
          use_reverse ? check.link.parent_from_child.inverse() : check.link.parent_from_child;
      if (!use_reverse) walk_.checked_with[child] = best;
      const PoseError gap = ComparePoses(world[best] * best_from_child, world[child]);
      if (gap.position_m <= options_.loop_tolerance_m && gap.angle_rad <= options_.loop_tolerance_rad) {
        // One check that itself needs a loop does not confirm one: two plan-view poses from
        // neighbouring scans agree on the same wrong street as readily as on the right one. Two
        // such checks from two more scans, placed by other links, do: three scans put this one on
        // one spot (issue 37: a busy tilted street, a station whose four plan-view links all fit
        // to 2 mm and all carried traffic in each other's free space stayed unregistered).
        if (needs_loop && check.NeedsLoop() && ++suspects_agreeing < kSuspectsThatConfirm) continue;
        closed_[child] = true;
        return false;
      }
      char buf[200];
      std::snprintf(buf, sizeof buf, "loop %s-%s-%s does not close: %.3f m / %.2f° apart", scans_[parent].name.c_str(),
                    scans_[child].name.c_str(), scans_[best].name.c_str(), gap.position_m, gap.angle_rad * 180 / M_PI);
      // A check that itself needs a loop cannot fail a sound link: it is the suspect, and fails
      // alone (measured on an office floor: a corridor pose turned 180°, weak for its object-sized
      // conflicts, failed the true link it checked).
      if (!needs_loop && check.NeedsLoop()) {
        const int check_parent = use_reverse ? child : best, check_child = use_reverse ? best : child;
        LogWarning(std::string(buf) + "; the check, which needed a loop itself, failed");
        book_.Fail(check_parent, check_child, std::string(buf) + "; this link needed a loop itself");
        continue;
      }
      // Both links are failed — unless only the link checked needs a loop: then it is the suspect,
      // and the sound check stays (it may place the child once the suspect is gone).
      const bool only_suspect = needs_loop && !check.NeedsLoop();
      LogWarning(std::string(buf) + (only_suspect ? "; the link that needed a loop failed" : "; both links failed"));
      book_.Fail(parent, child, buf);
      if (!only_suspect) book_.Fail(use_reverse ? child : best, use_reverse ? best : child, buf);
      FailWeakLinksOfLoop(parent, best, buf);
      return true;
    }
    // A lone pair (the child has no other candidate neighbour at all, whatever became of its links)
    // cannot close a loop: evidence against its pose leaves it weak; a plan-view pose without
    // features still fails.
    const bool lone = Lone(parent, child);
    if (needs_loop && (book_.At(parent, child).needs_loop || !lone)) {
      const std::string why = book_.At(parent, child).link.reason;
      const auto [alike, twin] = AlikeScan(parent, child);
      std::string reason = why.substr(0, why.find("; a loop"));
      const auto add = [&reason](const std::string& part) { reason += (reason.empty() ? "" : "; ") + part; };
      if (twin >= 0 && !book_.At(parent, child).NeedsLoop())
        add(scans_[alike].name + " looks the same from the spot of " + scans_[twin].name + " (a repeated room or corridor)");
      add("no loop through another scan confirms it");
      book_.Fail(parent, child, reason);
      book_.At(parent, child).unconfirmed = true;
      return true;
    }
    return false;
  }

  // The child has no other candidate neighbour at all, whatever became of its links.
  bool Lone(int parent, int child) const {
    for (int q = 0; q < n_; ++q)
      if (q != child && q != parent &&
          std::max(walk_.weights(q, child), walk_.weights(child, q)) >= source_.min_check_weight)
        return false;
    return true;
  }

  // Whether scan q is placed through `child` (child itself included).
  bool PlacedThrough(int q, int child) const {
    for (int a = q; a >= 0; a = order().parent[a])
      if (a == child) return true;
    return false;
  }

  // A weak-support tree link, in placement order.
  bool WeakSupport(int child) const {
    const int parent = order().parent[child];
    if (parent < 0 || choices_.kept.count({parent, child})) return false;
    const PairResult& r = book_.At(parent, child);
    // A plan-view pose rests on the surfaces alone, which a repeated building fits elsewhere as
    // well: measured on an office floor of identical rooms, a room and the corridor registered as
    // a project of their own were placed 9-25 m and 180° off at 22-40 % overlap, RMS at the noise
    // and no free-space conflict, the true pose never among the wall map's peaks. With other scans
    // around, the link's loops check it; without any, nothing can.
    return (r.weak_support && r.link.status == io::LinkStatus::kWeak) ||
           (r.surfaces_only && r.link.status == io::LinkStatus::kOk && Lone(parent, child));
  }

  // A loop longer than the child's own checks (CheckLink): a link between a scan placed through the
  // child and a verified scan outside that subtree that agrees with the chained poses closes a loop
  // through the weak link (a ring of stations: the ring's last link). It only confirms: a long
  // loop that does not close fails nothing (its error sums the drift of every link on it).
  // Pairs already registered come first; at most kLongLoopTries more are registered.
  bool LongLoopCloses(int child, const std::vector<bool>& verified) {
    std::vector<std::tuple<bool, int, int, int>> candidates;  // (not registered yet, -weight, outside, inside)
    for (int a = 0; a < n_; ++a) {
      if (a == child || !PlacedThrough(a, child)) continue;
      for (int b = 0; b < n_; ++b) {
        if (!verified[b] || PlacedThrough(b, child) || book_.Excluded(b, a) || book_.Excluded(a, b)) continue;
        const int w = std::max(walk_.weights(a, b), walk_.weights(b, a));
        if (w >= source_.min_check_weight) candidates.emplace_back(!book_.Find(b, a) && !book_.Find(a, b), -w, b, a);
      }
    }
    std::stable_sort(candidates.begin(), candidates.end(), [](const auto& x, const auto& y) {
      return std::tie(std::get<0>(x), std::get<1>(x)) < std::tie(std::get<0>(y), std::get<1>(y));
    });
    int registered = 0;
    for (const auto& [new_pair, neg_weight, b, a] : candidates) {
      const PairResult* reverse = book_.Find(a, b);
      const bool use_reverse = reverse && reverse->link.status != io::LinkStatus::kFailed;
      if (!use_reverse && !book_.Find(b, a) && registered++ >= kLongLoopTries) break;
      const PairResult& check = use_reverse ? *reverse : book_.Link(b, a);
      if (check.link.status == io::LinkStatus::kFailed || check.NeedsLoop() || check.weak_support) continue;
      const Eigen::Isometry3d b_from_a = use_reverse ? check.link.parent_from_child.inverse() : check.link.parent_from_child;
      const PoseError gap = ComparePoses(walk_.world[b] * b_from_a, walk_.world[a]);
      if (gap.position_m <= options_.loop_tolerance_m && gap.angle_rad <= options_.loop_tolerance_rad) {
        LogInfo(scans_[order().parent[child]].name + " -> " + scans_[child].name + ": confirmed by the loop through " +
                scans_[b].name + " - " + scans_[a].name);
        return true;
      }
    }
    return false;
  }

  // The tree links with weak support no loop closed on: their scans are placed but not verified.
  // Each link's reason says why no loop did (said once, however often the tree is walked again).
  void MarkUnconfirmedWeak() {
    if (!source_.loop_checks || !options_.verify_loops) return;
    std::vector<bool> confirmed(n_, false);  // weak-support links a loop closed on
    std::vector<int> weak;
    for (int child : order().order) {
      if (!WeakSupport(child)) continue;
      if (closed_[child]) confirmed[child] = true;
      else weak.push_back(child);
    }
    // Placed with no unconfirmed weak link on the way up from the root.
    auto verified_scans = [&]() {
      std::vector<bool> verified(n_, false);
      for (int q : order().order) {
        const int p = order().parent[q];
        verified[q] = p < 0 || (verified[p] && (!WeakSupport(q) || confirmed[q]));
      }
      return verified;
    };
    for (bool changed = true; changed;) {  // a confirmed link may verify the scans another's loop needs
      changed = false;
      for (int child : weak) {
        if (confirmed[child]) continue;
        const std::vector<bool> verified = verified_scans();
        if (verified[order().parent[child]] && LongLoopCloses(child, verified)) confirmed[child] = changed = true;
      }
    }
    for (int child : weak) {
      if (confirmed[child]) continue;
      walk_.unconfirmed_weak[child] = true;
      const int parent = order().parent[child];
      io::LinkRecord& link = book_.At(parent, child).link;
      if (link.status == io::LinkStatus::kOk) {  // a lone plan-view pose (WeakSupport)
        book_.At(parent, child).weak_support = true;
        link.status = io::LinkStatus::kWeak;
        link.reason = "plan-view pose: only the walls seen from above support it (" + std::to_string(link.consistent) +
                      " consistent correspondences), and a repeated room or corridor could fit them elsewhere";
      }
      std::string& why = link.reason;
      const std::string note = Lone(parent, child) ? "; no other scan is matched to it well enough to check it by a loop"
                                                   : "; no loop through another scan confirms it";
      if (why.find(note) == std::string::npos) why = why.substr(0, why.find("; a loop")) + note;
    }
  }

  // The tree links of a loop that does not close, beyond the two failed at once: the paths from
  // `parent` and from `best` up to their common ancestor. The loop is open through each of them;
  // those whose own evidence was weak are failed too (a 3-scan corridor: the open loop failed the
  // two links through the third scan and kept a weak link, RMS 3 x the noise, that had put its
  // scan 3.5 deg off); links with sound evidence stay, and their loops are checked in turn.
  void FailWeakLinksOfLoop(int parent, int best, const std::string& loop) {
    std::vector<int> up_from_best;
    for (int a = best; a >= 0; a = order().parent[a]) up_from_best.push_back(a);
    auto on_best_path = [&](int q) { return std::find(up_from_best.begin(), up_from_best.end(), q) != up_from_best.end(); };
    int ancestor = parent;
    while (ancestor >= 0 && !on_best_path(ancestor)) ancestor = order().parent[ancestor];
    std::vector<int> below;  // the scans whose tree links lie on the loop
    for (int a = parent; a >= 0 && a != ancestor; a = order().parent[a]) below.push_back(a);
    for (int a : up_from_best) {
      if (a == ancestor) break;
      below.push_back(a);
    }
    for (int q : below) {
      const int p = order().parent[q];
      if (p < 0 || choices_.kept.count({p, q})) continue;
      io::LinkRecord& link = book_.At(p, q).link;
      if (link.status != io::LinkStatus::kWeak) continue;
      const std::string why = loop + "; this link's evidence was weak (" + link.reason + ")";
      LogWarning(scans_[p].name + " -> " + scans_[q].name + ": failed: " + why);
      book_.Fail(p, q, why);
    }
  }

  // A link that needs a loop and is not in the settled tree was never confirmed by one: it is
  // failed, not left "weak" beside the links that placed the scans (measured on a symmetric office
  // floor: rooms put on each other's spots, 92 % overlap, listed as weak links, 9-16 m off).
  void FailUnconfirmed() {
    std::vector<std::pair<int, int>> unconfirmed;
    for (const auto& [key, result] : book_.done()) {
      const auto [parent, child] = key;
      if (!result.needs_loop || result.link.status == io::LinkStatus::kFailed) continue;
      if (order().parent[child] == parent || choices_.kept.count(key)) continue;
      unconfirmed.push_back(key);
    }
    for (const auto& [parent, child] : unconfirmed) {
      const std::string why = book_.At(parent, child).link.reason;
      book_.Fail(parent, child, why.substr(0, why.find("; a loop")) + "; not used: no loop confirms it");
    }
  }

  // A scan some pair put on another scan's spot (PairResult::same_spot) looks the same from there:
  // that other scan (the twin), or -1. `alike` is the link's parent or child; a twin that free space
  // refutes in its place on the link does not count (TwinRefuted).
  int Twin(int parent, int child, int alike) const {
    for (int q = 0; q < n_; ++q) {
      if (q == child || q == parent) continue;
      const PairResult* a = book_.Find(q, alike);
      const PairResult* b = book_.Find(alike, q);
      if (!(a && a->same_spot) && !(b && b->same_spot)) continue;
      const Eigen::Isometry3d alike_from_q =
          b && b->same_spot ? b->link.parent_from_child : a->link.parent_from_child.inverse();
      if (!TwinRefuted(parent, child, alike, q, alike_from_q)) return q;
    }
    return -1;
  }

  // Whether free space refutes twin q in the place of `alike` on the link parent -> child: the twin
  // put there (alike_from_q, its look-alike pose) leaves clearly more points in the other scanner's
  // free space than the link's own scan (FreeSpaceRefutes). Then the link's evidence is its scan's
  // own (measured on an office floor whose corridor ends look alike: each end station's link to its
  // neighbour, 8 m apart, refuted the other end station in its place by the furniture of the rooms
  // they see through the doors).
  bool TwinRefuted(int parent, int child, int alike, int q, const Eigen::Isometry3d& alike_from_q) const {
    if (!source_.violation_rate) return false;
    const auto key = std::make_tuple(parent, child, q);
    if (const auto it = twin_refuted_.find(key); it != twin_refuted_.end()) return it->second;
    const PairResult& link = book_.At(parent, child);
    const Eigen::Isometry3d& pose = link.link.parent_from_child;
    const double rate = alike == child ? source_.violation_rate(parent, q, pose * alike_from_q)
                                       : source_.violation_rate(q, child, alike_from_q.inverse() * pose);
    const bool refuted = FreeSpaceRefutes(link.violation_rate, rate);
    twin_refuted_.emplace(key, refuted);
    if (refuted) {
      char buf[400];
      std::snprintf(buf, sizeof buf,
                    "%s -> %s: %s looks the same from the spot of %s, but %s in its place leaves %.2f %% of the "
                    "samples in free space against %.2f %%: the link is %s's own",
                    scans_[parent].name.c_str(), scans_[child].name.c_str(), scans_[alike].name.c_str(),
                    scans_[q].name.c_str(), scans_[q].name.c_str(), 100 * rate, 100 * link.violation_rate,
                    scans_[alike].name.c_str());
      LogInfo(buf);
    }
    return refuted;
  }

  // Whether the tree link needs a loop: its own evidence says so, or its child has a twin — a room
  // station that fits another room's station on its spot fits that room as well as its own
  // (measured: a room station placed in front of the wrong corridor station by 7 consistent
  // correspondences, 38.6 % overlap and no conflict, 16 m off; another put on its twin's spot across
  // the corridor by a plan-view pose, "ok", 40 % overlap, no conflict, 9.7 m off). A pose on the
  // surfaces alone is as ambiguous as its parent too: a corridor station fits the room of one
  // station as well as its twin's (measured: a corridor station placed by a room station it never
  // saw, 24 m apart, 16 m off, "ok" with 37 % overlap and no conflict). Feature-supported links
  // from a parent with a twin stay: a busy street's stations with a 180° twin kept 5 of 6 scans,
  // all right; asking their links for loops too kept 3.
  bool NeedsLoop(int parent, int child) const {
    return book_.At(parent, child).NeedsLoop() || AlikeScan(parent, child).second >= 0;
  }
  // The scan of the link that has a twin, and the twin: the child's first, then — for a pose on the
  // surfaces alone — the parent's; {-1, -1} when neither counts.
  std::pair<int, int> AlikeScan(int parent, int child) const {
    if (const int twin = Twin(parent, child, child); twin >= 0) return {child, twin};
    if (book_.At(parent, child).surfaces_only)
      if (const int twin = Twin(parent, child, parent); twin >= 0) return {parent, twin};
    return {-1, -1};
  }

  const std::vector<Scan>& scans_;
  const ScanOrderChoices& choices_;
  const LinkSource& source_;
  const RegisterOptions& options_;
  const CancelToken& cancel_;
  PairBook& book_;
  const int n_;
  const bool priors_;
  std::vector<bool> position_tried_;
  static constexpr int kLongLoopTries = 3;  // pair registrations a long loop may add (LongLoopCloses)
  std::vector<bool> closed_;  // per scan: a loop closed on its tree link in the last round of checks
  TreeWalk walk_;
  mutable std::map<std::tuple<int, int, int>, bool> twin_refuted_;  // TwinRefuted by (parent, child, twin)
};

}  // namespace

Expected<TreeWalk> WalkTree(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                            const RegisterOptions& options, const CancelToken& cancel, PairBook& book) {
  return Walker(scans, choices, source, options, cancel, book).Run();
}

}  // namespace scanreg::pipeline

