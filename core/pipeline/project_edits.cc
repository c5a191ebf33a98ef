#include "core/pipeline/project_edits.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <vector>

#include "core/io/control_file.h"
#include "core/io/project_tree.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {
using io::IsTreeLink;

namespace {

// `text` with every whole-word `from` (not inside a longer name: s1 is not in s10) made `to`.
std::string ReplaceName(const std::string& text, const std::string& from, const std::string& to) {
  const auto name_char = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; };
  std::string out;
  std::size_t at = 0;
  for (std::size_t k = text.find(from); k != std::string::npos; k = text.find(from, k + 1)) {
    const std::size_t end = k + from.size();
    if (k < at || (k > 0 && name_char(text[k - 1])) || (end < text.size() && name_char(text[end]))) continue;
    out += text.substr(at, k - at) + to;
    at = end;
  }
  return out + text.substr(at);
}

// Whether `text` names `scan` as a whole word.
bool Names(const std::string& text, const std::string& scan) { return ReplaceName(text, scan, "") != text; }

// A scan left "not verified" because it was placed through `through`, which is registered now:
// its reason says so and what to do, instead of calling `through` not verified (issue 33).
void ScansPlacedThroughAreNowPlaceable(const std::string& through, io::Project& project) {
  const std::string stale = "not verified: placed through " + through + ", which is not verified";
  for (io::ProjectScan& ps : project.scans)
    if (!ps.registered && ps.unregistered_reason == stale)
      ps.unregistered_reason = "not verified: placed through " + through + " when " + through +
                               " was not verified; it is registered now: register again to place " + ps.name;
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
  // An unregistered scan of a cluster brings its cluster along: the one link places them all.
  const std::string cluster = project.scans[c].registered ? std::string() : project.scans[c].cluster;
  std::vector<int> moved =
      project.scans[c].registered ? io::ScansRegisteredThrough(project, c) : std::vector<int>{c};
  if (!cluster.empty())
    for (int i = 0; i < static_cast<int>(project.scans.size()); ++i)
      if (i != c && !project.scans[i].registered && project.scans[i].cluster == cluster) moved.push_back(i);
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
  const Eigen::Isometry3d delta = project.scans[c].registered || !cluster.empty()
                                      ? Eigen::Isometry3d(new_pose * project.scans[c].world_from_scan.inverse())
                                      : Eigen::Isometry3d::Identity();
  if (!cluster.empty()) {
    // The cluster's links from its root down to the child turn round: the child is now where the
    // cluster hangs from, and each scan keeps one link to its parent.
    std::string cur = link.child;
    for (std::size_t steps = 0; cur != cluster && steps < project.links.size(); ++steps) {
      auto up = std::find_if(project.links.begin(), project.links.end(),
                             [&](const io::LinkRecord& l) { return IsTreeLink(l) && l.child == cur; });
      if (up == project.links.end()) break;
      std::swap(up->parent, up->child);
      up->parent_from_child = up->parent_from_child.inverse();
      cur = up->child;
    }
    for (int i : moved) {
      project.scans[i].registered = true;
      project.scans[i].cluster.clear();
      project.scans[i].unregistered_reason.clear();
      project.scans[i].unverified = false;
    }
  }
  for (int i : moved) {
    project.scans[i].world_from_scan = delta * project.scans[i].world_from_scan;
    // The stored coarse pose belongs to the automatic run this edit replaces (the report's
    // "after coarse" errors would otherwise describe a registration that is no longer there).
    project.scans[i].coarse_world_from_scan.reset();
  }
  project.scans[c].world_from_scan = new_pose;
  project.scans[c].registered = true;
  project.scans[c].unregistered_reason.clear();
  project.scans[c].unverified = false;
  project.scans[c].manual_pose = false;
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
  added.user_accepted = true;  // the user chose it: kept by later registrations
  links.push_back(added);
  for (int i : moved) ScansPlacedThroughAreNowPlaceable(project.scans[i].name, project);
  ScansPlacedThroughAreNowPlaceable(link.child, project);
  return Status::Ok();
}

Status SetLinkDecision(const std::string& parent, const std::string& child, LinkDecision decision,
                       io::Project& project) {
  for (const std::string& name : {parent, child})
    if (project.FindScan(name) < 0)
      return MakeError(ErrorCode::kInvalidArgument, "'" + name + "' is not a scan of the project");
  bool found = false;
  for (io::LinkRecord& l : project.links) {
    if (l.parent != parent || l.child != child) continue;
    l.user_accepted = decision == LinkDecision::kAccept;
    l.user_rejected = decision == LinkDecision::kReject;
    found = true;
  }
  if (!found) {
    return MakeError(ErrorCode::kInvalidArgument, "no link " + parent + " -> " + child +
                                                      " is listed in the project; register it first (the links are "
                                                      "listed parent first, as register prints them)");
  }
  return Status::Ok();
}

Status SetScanPose(const std::string& scan, const Eigen::Isometry3d& world_from_scan, bool move_dependents,
                   io::Project& project) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  const Eigen::Matrix4d m = world_from_scan.matrix();
  if (!m.allFinite()) {
    return MakeError(ErrorCode::kInvalidArgument, "the pose of '" + scan + "' has a non-finite number; re-enter it");
  }
  const Eigen::Matrix3d r = world_from_scan.linear();
  if (std::abs(r.determinant() - 1.0) > 1e-6 || !(r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-6)) {
    return MakeError(ErrorCode::kInvalidArgument, "the pose of '" + scan +
                                                      "' is not a rigid motion (rotation not orthonormal); "
                                                      "enter angles, or a 4x4 matrix with a rotation block");
  }
  io::ProjectScan& ps = project.scans[s];
  const std::vector<int> moved =
      move_dependents && ps.registered ? io::ScansRegisteredThrough(project, s) : std::vector<int>{s};
  const Eigen::Isometry3d delta =
      ps.registered ? Eigen::Isometry3d(world_from_scan * ps.world_from_scan.inverse()) : Eigen::Isometry3d::Identity();
  for (int i : moved) {
    project.scans[i].world_from_scan = delta * project.scans[i].world_from_scan;
    project.scans[i].coarse_world_from_scan.reset();
  }
  ps.world_from_scan = world_from_scan;
  ps.registered = true;
  ps.manual_pose = true;
  ps.unregistered_reason.clear();
  ps.unverified = false;
  return Status::Ok();
}

Status ReleaseHandPlacement(const std::string& scan, io::Project& project) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  io::ProjectScan& ps = project.scans[s];
  if (!ps.manual_pose) {
    return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' was not placed by hand; nothing to release");
  }
  ps.manual_pose = false;
  ps.registered = false;
  ps.unverified = false;
  ps.unregistered_reason = "released from its hand placement; register to place it";
  return Status::Ok();
}

Expected<OverrideOutcome> OverrideParent(io::Project& project, ScanStore& scans,
                                         const std::string& child, const std::optional<std::string>& parent,
                                         RegisterOptions options, ProgressSink& progress, const CancelToken& cancel) {
  const int c = project.FindScan(child);
  if (c < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + child + "' is not a scan of the project");
  if (parent && (project.FindScan(*parent) < 0 || *parent == child)) {
    return MakeError(ErrorCode::kInvalidArgument, "'" + *parent + "' cannot be the parent of '" + child +
                                                      "'; choose another scan of the project");
  }
  if (parent && project.root == child) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "'" + child + "' is the root of the scan order and has no parent; set another root first");
  }
  io::Project after = project;
  after.scans[c].parent_override = parent;
  options.only_scans = {child};
  if (!project.scans[c].cluster.empty())  // its cluster goes with it
    for (const io::ProjectScan& s : project.scans)
      if (s.name != child && !s.registered && s.cluster == project.scans[c].cluster) options.only_scans.push_back(s.name);
  if (project.scans[c].registered)
    for (int i : io::ScansRegisteredThrough(project, c))
      if (i != c) options.only_scans.push_back(project.scans[i].name);
  Expected<ProjectRegistration> r = RegisterProjectScans(after, scans, options, progress, cancel);
  if (!r) return r.error();
  OverrideOutcome out;
  out.confusion = r->confusion;
  const io::ProjectScan& now = after.scans[c];
  std::string old_parent;
  for (const io::LinkRecord& l : project.links)
    if (IsTreeLink(l) && l.child == child) old_parent = l.parent;
  if (!now.registered && project.scans[c].registered) {
    out.message = "the link of " + child + " to " + parent.value_or("another scan") + " failed (" +
                  now.unregistered_reason + "); " + child + " keeps its " +
                  (old_parent.empty() ? std::string("pose") : "link to " + old_parent) +
                  " and the override was not kept";
    return out;
  }
  std::string new_parent;
  for (const io::LinkRecord& l : after.links)
    if (IsTreeLink(l) && l.child == child) new_parent = l.parent;
  out.applied = true;
  out.message = now.registered ? child + " registered to " + new_parent + " (" + std::to_string(options.only_scans.size()) +
                                     " scan(s) re-registered)"
                               : child + " stays unregistered: " + now.unregistered_reason;
  project = std::move(after);
  return out;
}

Expected<std::vector<std::string>> RemoveScan(const std::string& scan, io::Project& project) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  std::vector<std::string> orphans;
  for (const io::LinkRecord& l : project.links)
    if (IsTreeLink(l) && l.parent == scan) orphans.push_back(l.child);
  if (const Eigen::MatrixXi* c = project.CurrentConfusion()) {
    Eigen::MatrixXi kept(c->rows() - 1, c->cols() - 1);
    for (int i = 0, r = 0; i < c->rows(); ++i) {
      if (i == s) continue;
      for (int k = 0, q = 0; k < c->cols(); ++k)
        if (k != s) kept(r, q++) = (*c)(i, k);
      ++r;
    }
    project.confusion = kept;
    project.confusion_scans.erase(project.confusion_scans.begin() + s);
  } else {
    project.confusion.resize(0, 0);
    project.confusion_scans.clear();
  }
  project.scans.erase(project.scans.begin() + s);
  project.links.erase(std::remove_if(project.links.begin(), project.links.end(),
                                     [&](const io::LinkRecord& l) { return l.parent == scan || l.child == scan; }),
                      project.links.end());
  for (io::ProjectScan& p : project.scans)
    if (p.parent_override == scan) p.parent_override.reset();
  if (project.root == scan) project.root.reset();
  project.targets.erase(std::remove_if(project.targets.begin(), project.targets.end(),
                                       [&](const io::TargetRecord& t) { return t.scan == scan; }),
                        project.targets.end());
  // A scan left out of the registration for a reason that names the removed scan: the reason no
  // longer holds, and says so.
  for (io::ProjectScan& p : project.scans)
    if (!p.registered && Names(p.unregistered_reason, scan))
      p.unregistered_reason = "its registration went through " + scan + ", which was removed from the project; register "
                              "again to place " + p.name;
  return orphans;
}

Status RenameScan(const std::string& scan, const std::string& new_name, io::Project& project) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  if (new_name.empty() || new_name.size() > 200 ||
      std::any_of(new_name.begin(), new_name.end(), [](unsigned char c) { return c < 0x20 || c == 0x7f; })) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "a scan name must be 1 to 200 printable characters; choose another name for '" + scan + "'");
  }
  if (new_name == scan) return Status::Ok();
  if (project.FindScan(new_name) >= 0) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "another scan is already named '" + new_name + "'; choose a name no scan has");
  }
  project.scans[s].name = new_name;
  for (io::LinkRecord& l : project.links) {
    if (l.parent == scan) l.parent = new_name;
    if (l.child == scan) l.child = new_name;
  }
  for (io::ProjectScan& p : project.scans)
    if (p.parent_override == scan) p.parent_override = new_name;
  if (project.root == scan) project.root = new_name;
  for (std::string& n : project.confusion_scans)
    if (n == scan) n = new_name;
  for (io::TargetRecord& t : project.targets)
    if (t.scan == scan) t.scan = new_name;
  // The reasons name scans too (a loop, a twin, the scan a weak link came from).
  for (io::LinkRecord& l : project.links) l.reason = ReplaceName(l.reason, scan, new_name);
  for (io::ProjectScan& p : project.scans) p.unregistered_reason = ReplaceName(p.unregistered_reason, scan, new_name);
  return Status::Ok();
}

Status SetRoot(const std::string& scan, io::Project& project) {
  const int s = project.FindScan(scan);
  if (s < 0) return MakeError(ErrorCode::kInvalidArgument, "'" + scan + "' is not a scan of the project");
  project.root = scan;
  project.scans[s].parent_override.reset();
  return Status::Ok();
}

Status ImportControl(const std::filesystem::path& file, const std::vector<std::string>& check_points,
                     io::Project& project) {
  Expected<std::vector<io::ControlPoint>> control = io::ReadControlFile(file);
  if (!control) return control.error();
  if (Status s = io::MarkCheckPoints(check_points, &*control); !s) return s;
  project.control = std::move(*control);
  project.georef.reset();
  return Status::Ok();
}

Status AddPickedTarget(io::Project& project, const io::TargetRecord& target) {
  if (project.FindScan(target.scan) < 0)
    return MakeError(ErrorCode::kNotFound, "pick a target: no scan '" + target.scan + "' in the project");
  if (!target.center.allFinite() || !(target.sigma_m > 0))
    return MakeError(ErrorCode::kInvalidArgument, "pick a target in " + target.scan + ": the centre is not a point");
  if (target.name.find_first_of(",\r\n") != std::string::npos)
    return MakeError(ErrorCode::kInvalidArgument, "target name '" + target.name + "' holds a comma or a line break");
  io::TargetRecord t = target;
  t.kind = "picked";
  t.named_by_user = !t.name.empty();
  t.residual_m = -1;
  auto& targets = project.targets;
  targets.erase(std::remove_if(targets.begin(), targets.end(),
                               [&](const io::TargetRecord& old) {
                                 return old.kind == "picked" && old.scan == t.scan &&
                                        ((!t.name.empty() && old.name == t.name) || (old.center - t.center).norm() < 0.02);
                               }),
                targets.end());
  targets.push_back(t);
  return Status::Ok();
}

}  // namespace scanreg::pipeline
