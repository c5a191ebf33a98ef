// The scan-order tree of a saved project, read from its links: which links the poses are chained
// along, the order in which the registration placed the scans, and which scans hang below a scan.
// Shared by the report, the GUI and the user's edits (pipeline/project_edits.h).
#pragma once

#include <vector>

#include "core/io/project.h"

namespace scanreg::io {

// A link the poses are chained along: not a loop check, not failed, not rejected by the user.
bool IsTreeLink(const LinkRecord& link);

// Scan indices in scan order (W §2 step 4): the root, then each child of a tree link in the order
// the links were placed, then the scans the tree does not reach, in project order.
std::vector<int> OrderedScanIndices(const Project& project);

// `root` and every scan registered through it along tree links (root first).
std::vector<int> ScansRegisteredThrough(const Project& project, int root);

// Per scan: its pose rests on a hand placement — it was placed by hand, or registered through a
// scan that was (issue 14: such a pose is shown as such everywhere, never as plain "registered").
std::vector<bool> RestsOnHandPlacement(const Project& project);

}  // namespace scanreg::io
