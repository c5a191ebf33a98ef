// Scan order: which scan is registered to which (W §3.3, SPEC §2 step 4).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <utility>
#include <vector>

#include "core/common/expected.h"

namespace scanreg {

// A spanning tree over the scans, grown from the root in placement order.
struct ScanOrder {
  int root = -1;
  std::vector<int> parent;    // per scan; -1 for the root and for unplaced scans
  std::vector<int> order;     // placement order, root first; every parent precedes its children
  std::vector<int> unplaced;  // scans no usable edge reaches, ascending
};

// Prim-style maximum spanning tree on the directed confusion graph (W §3.3).
//
// confusion: n x n, C(i, j) = accepted matches of i's descriptors in j; the diagonal (feature
//   counts) is ignored. Edge direction: the edge parent -> child has weight C(parent, child),
//   as in W ("C(i, j) is the weight of the edge from node i to node j"; the set of placed scans
//   grows along the heaviest edge from a placed scan to an unplaced one).
// root: the first scan; default: the tail i of the heaviest off-diagonal edge C(i, j)
//   (ties: lowest i, then lowest j), among scans without a parent override.
// parent_override: empty or one entry per scan; a set entry makes that scan's parent fixed. The
//   scan is placed as soon as its override parent is placed, regardless of weights and of
//   min_weight. An override that is self-referential, out of range, on the root or part of a
//   cycle is an error naming the scans. If the overridden edge is also excluded, the scan stays
//   unplaced (the user's choice is not silently replaced).
// excluded_edges: (parent, child) links known to have failed; never used.
// min_weight: edges lighter than this are not used (0 allows any edge, including empty ones).
// Ties are broken by the lowest child index, then the lowest parent index (deterministic).
Expected<ScanOrder> ComputeScanOrder(const Eigen::MatrixXi& confusion, std::optional<int> root,
                                     const std::vector<std::optional<int>>& parent_override,
                                     const std::vector<std::pair<int, int>>& excluded_edges,
                                     int min_weight = 1);

}  // namespace scanreg
