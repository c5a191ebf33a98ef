// The user's edits of a registered project that change poses: applying a pair registration the
// user chose (the GUI pair panel's "use this result") and placing a scan by hand. Both move the
// scans registered through the edited scan with it, so that their relative poses are kept.
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/scan_store.h"

namespace scanreg::pipeline {

// The link becomes the child's tree link and the child, with every scan registered through it,
// moves by the change of the child's pose.
// Errors (kInvalidArgument, naming the scans and what to do): unknown scan, a failed link, an
// unregistered parent, a parent registered through the child (the tree would have a cycle).
// When the child's tree parent changes, the parent becomes its parent override, so that a later
// re-registration keeps the user's choice. The link is marked accepted: the user chose it, and a
// later registration uses it as it is (UserChoices::kept).
Status ApplyPairResult(const io::LinkRecord& link, io::Project& project);

// The user's decision on the listed link parent -> child (every record of that pair): an accepted
// link is kept as it is by later registrations (a weak link whose scan was "not verified" then
// places it), a rejected one is never used; kClear forgets the decision. The poses do not change
// until the next registration. Errors (kInvalidArgument): an unknown scan, or no such link listed.
enum class LinkDecision { kAccept, kReject, kClear };
Status SetLinkDecision(const std::string& parent, const std::string& child, LinkDecision decision,
                       io::Project& project);

// Places `scan` at `world_from_scan` by hand: it becomes registered with a manual pose (no link
// evidence; see ProjectScan::manual_pose). With `move_dependents`, the scans registered through it
// move along (moving the root with its dependents moves the whole registered project, e.g. into
// a site frame). Errors: unknown scan; non-finite numbers; a rotation that is not rigid
// (|det − 1| or R·Rᵀ − I off by more than 1e-6).
Status SetScanPose(const std::string& scan, const Eigen::Isometry3d& world_from_scan, bool move_dependents,
                   io::Project& project);

// Lets the registration place a scan that was placed by hand: it keeps its pose as the starting
// point but is no longer held (unregistered until the next registration). Error when it was not
// placed by hand.
Status ReleaseHandPlacement(const std::string& scan, io::Project& project);

// Project management (issue 14, item 6). Each names the scan and what to do when it refuses.
// Removes a scan with its links, the overrides naming it, its confusion row and column (the root
// moves to no scan when it was the root). The scans registered through it keep their poses, without
// a link to it: returned by name, so that the user can be told to register them again.
Expected<std::vector<std::string>> RemoveScan(const std::string& scan, io::Project& project);
// Renames a scan everywhere the project names it (links, overrides, root, confusion). The new name
// must be non-empty, printable, at most 200 characters and not another scan's.
Status RenameScan(const std::string& scan, const std::string& new_name, io::Project& project);
// Makes `scan` the root of the scan order (its parent override goes: the root has no parent). The
// root keeps its pose in the next registration; the others are placed relative to it.
Status SetRoot(const std::string& scan, io::Project& project);

// Registers `child` to `parent` (a parent override; none: let the registration choose again),
// re-registering only the child and the scans registered through it; every other scan keeps its
// pose and link. When the forced link fails and the child had a link before, the project is left
// as it was — the old link stays and the override is not kept — and the outcome says why.
// `scans`: the project's scans (points), in project order (a store: read on demand). Errors: unknown scans, the root given a
// parent, the registration's errors (cancel, invalid options).
struct OverrideOutcome {
  bool applied = false;  // false: the old link stays
  std::string message;   // what happened, for the log and a dialog
  Eigen::MatrixXi confusion;
};
Expected<OverrideOutcome> OverrideParent(io::Project& project, ScanStore& scans,
                                         const std::string& child, const std::optional<std::string>& parent,
                                         RegisterOptions options, ProgressSink& progress, const CancelToken& cancel);

// Survey control (issue 15): the points of a control file (io::ReadControlFile) replace the
// project's, `check_points` among them become check points, and the last adjustment's residuals
// (against other control) are dropped. Errors name the file and line, or the unknown check point;
// the project is unchanged then.
Status ImportControl(const std::filesystem::path& file, const std::vector<std::string>& check_points,
                     io::Project& project);

// A target the user picked in a scan (kind "picked"; a name ties it to the control point of that
// name): replaces the scan's earlier pick of the same name or within 2 cm. Kept through every later
// registration and used by the next georeferencing. Errors: an unknown scan, a centre not finite,
// a name with a comma or a line break (control files are CSV).
Status AddPickedTarget(io::Project& project, const io::TargetRecord& target);

}  // namespace scanreg::pipeline
