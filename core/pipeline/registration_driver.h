// The one registration driver behind RegisterScans (links from feature matches, W §2) and
// RegisterFromCurrentPoses (links from the overlap at the current poses): the scan order over the
// link weights with each failed link replaced by the next-best edge, loop checks, world poses
// chained from the root, the global step, and the reason of every scan left out. What differs
// between the two paths is a LinkSource; the per-scan data (features, samples) are prepared once by
// the caller, before the driver runs.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_pair.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {

struct LinkSource {
  // Edge weights of the scan order: weights(i, j) for parent i, child j (feature matches, or the
  // overlap in per mille); edges below min_weight are not links.
  Eigen::MatrixXi weights;
  int min_weight = 1;
  // Registers child to parent (called at most once per ordered pair).
  std::function<PairResult(int parent, int child)> register_pair;
  // The free-space violation rate of a pair at a pose (AlignmentEvidence::ViolationRate), to test
  // a look-alike scan in a link's place (tree_walk.h). Empty: look-alikes are not tested.
  std::function<double(int parent, int child, const Eigen::Isometry3d& parent_from_child)> violation_rate;
  const char* verb = "registering";  // progress: "registering s02 to s01"
  // Loop checks (beyond W): each tree link is also verified against the child's best other
  // neighbour by weight (min_check_weight or more); a loop that does not close fails both links.
  bool loop_checks = true;
  int min_check_weight = 1;
  // Extra links for the global step besides the loop checks: every other pair whose overlap(i, j)
  // or overlap(j, i) reaches `extra_overlap` (empty matrix: none), registered with the larger
  // overlap's scan as the parent.
  Eigen::MatrixXd overlap;
  double extra_overlap = 0.0;
  // At most this many of those extra links per scan, its largest overlaps (a pair stays when either
  // of its scans ranks it so high); 0: every one.
  int extra_per_scan = 0;
  // Without `overlap` (links from feature matches): the overlap at the registered poses, computed once
  // the tree has placed the scans (placed[i]: scan i is registered), and the refinement of a pair
  // from those poses (parent_from_child). Every other pair overlapping by extra_overlap is refined
  // and joins the global step (issue 13, item 3: the pairs candidate selection did not match).
  std::function<Eigen::MatrixXd(const std::vector<Eigen::Isometry3d>& world, const std::vector<bool>& placed)> overlap_at;
  std::function<PairResult(int parent, int child, const Eigen::Isometry3d& parent_from_child)> refine_pair;
  // Whether pair results carry a coarse pose (W fig. 6 "after coarse"), and the reason given to a
  // scan no link reaches.
  bool has_coarse = true;
  // Partners by position: a scan the weights leave unplaced is also tried against up to this many
  // placed scans nearest to its prior pose or to its placed neighbours in capture order (0: none).
  int position_partners = 0;
  std::string no_link_reason;
  // Clusters (issue 14): the scans the tree leaves out are registered to each other along trees of
  // their own (heaviest edge first; no loop checks), so that one link places each group later.
  bool clusters = false;
};

// Runs the driver on prepared scans; `result` arrives with the timings and the confusion matrix of
// the preparation and leaves with the scan order, poses, links and reasons.
Status DriveRegistration(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                         const RegisterOptions& options, ProgressSink& progress, const CancelToken& cancel,
                         ProjectRegistration* result);

// The user's links hold exactly (after a step that moves every scan, e.g. the pose graph): parents
// first, each child of a kept link and the scans under it move back onto its link.
void HoldKeptLinks(const ScanOrderChoices& choices, ProjectRegistration* result);

}  // namespace scanreg::pipeline
