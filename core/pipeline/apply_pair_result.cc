#include "core/pipeline/apply_pair_result.h"

#include <algorithm>
#include <vector>

namespace scanreg::pipeline {
namespace {

bool IsTreeLink(const io::LinkRecord& l) {
  return !l.loop_check && !l.user_rejected && l.status != io::LinkStatus::kFailed;
}

// Scans registered through `root` along the tree links (root included).
std::vector<int> Subtree(const io::Project& project, int root) {
  std::vector<int> out{root};
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::string& name = project.scans[out[k]].name;
    for (const io::LinkRecord& l : project.links) {
      if (!IsTreeLink(l) || l.parent != name) continue;
      const int c = project.FindScan(l.child);
      if (c >= 0 && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
    }
  }
  return out;
}

}  // namespace

Status ApplyPairResult(const io::LinkRecord& link, io::Project& project) {
  const int p = project.FindScan(link.parent), c = project.FindScan(link.child);
  if (p < 0 || c < 0 || p == c) {
    return MakeError(ErrorCode::kInvalidArgument, "the pair " + link.child + " → " + link.parent +
                                                      " does not name two scans of the project; reload the project");
  }
  if (link.status == io::LinkStatus::kFailed) {
    return MakeError(ErrorCode::kInvalidArgument, "the registration of " + link.child + " to " + link.parent +
                                                      " failed (" + link.reason +
                                                      "); try another method or set the parent by hand");
  }
  if (!project.scans[p].registered) {
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + link.parent +
                                                      "' is not registered; register the project first or run "
                                                      "the pair the other way round");
  }
  const std::vector<int> moved = project.scans[c].registered ? Subtree(project, c) : std::vector<int>{c};
  if (std::find(moved.begin(), moved.end(), p) != moved.end()) {
    return MakeError(ErrorCode::kInvalidArgument, "scan '" + link.parent + "' is registered through '" + link.child +
                                                      "'; registering " + link.child +
                                                      " to it would make a cycle. "
                                                      "Change the parent of " +
                                                      link.parent + " first");
  }
  std::string old_parent;
  for (const io::LinkRecord& l : project.links)
    if (IsTreeLink(l) && l.child == link.child) old_parent = l.parent;

  const Eigen::Isometry3d new_pose = project.scans[p].world_from_scan * link.parent_from_child;
  const Eigen::Isometry3d delta = project.scans[c].registered
                                      ? Eigen::Isometry3d(new_pose * project.scans[c].world_from_scan.inverse())
                                      : Eigen::Isometry3d::Identity();
  for (int i : moved) {
    project.scans[i].world_from_scan = delta * project.scans[i].world_from_scan;
    // The stored coarse pose belongs to the automatic run this edit replaces (the report's
    // "after coarse" errors would otherwise describe a registration that is no longer there).
    project.scans[i].coarse_world_from_scan.reset();
  }
  project.scans[c].world_from_scan = new_pose;
  project.scans[c].registered = true;
  project.scans[c].unregistered_reason.clear();
  if (old_parent != link.parent && project.root != link.child) project.scans[c].parent_override = link.parent;

  // The new link replaces the child's tree link and any earlier record of the same pair.
  auto& links = project.links;
  links.erase(std::remove_if(links.begin(), links.end(),
                             [&](const io::LinkRecord& l) {
                               return l.child == link.child && (IsTreeLink(l) || l.parent == link.parent);
                             }),
              links.end());
  io::LinkRecord added = link;
  added.loop_check = false;
  added.user_rejected = false;
  added.user_accepted = link.status == io::LinkStatus::kWeak;
  links.push_back(added);
  return Status::Ok();
}

}  // namespace scanreg::pipeline
