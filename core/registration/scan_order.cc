#include "core/registration/scan_order.h"

#include <algorithm>
#include <set>
#include <string>

namespace scanreg {
namespace {

std::string ChainText(const std::vector<int>& chain) {
  std::string s;
  for (std::size_t k = 0; k < chain.size(); ++k) s += (k ? " -> " : "") + std::to_string(chain[k]);
  return s;
}

// Checks ranges and that following overrides child -> parent never loops.
Status CheckOverrides(const std::vector<std::optional<int>>& parent_override, int n) {
  for (int i = 0; i < n; ++i) {
    if (!parent_override[i]) continue;
    const int p = *parent_override[i];
    if (p < 0 || p >= n)
      return MakeError(ErrorCode::kInvalidArgument, "parent override of scan " + std::to_string(i) + " names scan " +
                                                        std::to_string(p) + ", which does not exist (0.." +
                                                        std::to_string(n - 1) + ")");
    if (p == i)
      return MakeError(ErrorCode::kInvalidArgument,
                       "scan " + std::to_string(i) + " is given itself as parent; choose another scan");
  }
  for (int start = 0; start < n; ++start) {
    std::vector<int> chain{start};
    std::vector<char> seen(n, 0);
    seen[start] = 1;
    int cur = start;
    while (parent_override[cur]) {
      cur = *parent_override[cur];
      chain.push_back(cur);
      if (seen[cur]) {
        return MakeError(ErrorCode::kInvalidArgument,
                         "parent overrides form a cycle (child -> parent): " + ChainText(chain) +
                             "; remove one of these overrides");
      }
      seen[cur] = 1;
    }
  }
  return Status::Ok();
}

}  // namespace

Expected<ScanOrder> ComputeScanOrder(const Eigen::MatrixXi& confusion, std::optional<int> root,
                                     const std::vector<std::optional<int>>& parent_override,
                                     const std::vector<std::pair<int, int>>& excluded_edges, int min_weight) {
  const int n = static_cast<int>(confusion.rows());
  if (confusion.rows() != confusion.cols())
    return MakeError(ErrorCode::kInvalidArgument, "confusion matrix is " + std::to_string(confusion.rows()) + " x " +
                                                      std::to_string(confusion.cols()) + "; it must be square");
  if (n == 0) return MakeError(ErrorCode::kInvalidArgument, "no scans to order (empty confusion matrix)");
  if (!parent_override.empty() && static_cast<int>(parent_override.size()) != n)
    return MakeError(ErrorCode::kInvalidArgument, "parent overrides list " + std::to_string(parent_override.size()) +
                                                      " scans but the confusion matrix has " + std::to_string(n));
  if (min_weight < 0) return MakeError(ErrorCode::kInvalidArgument, "min_weight must be >= 0");
  std::vector<std::optional<int>> overrides = parent_override;
  overrides.resize(n);
  if (Status s = CheckOverrides(overrides, n); !s) return s.error();

  std::set<std::pair<int, int>> excluded;
  for (const auto& [p, c] : excluded_edges) {
    if (p < 0 || p >= n || c < 0 || c >= n)
      return MakeError(ErrorCode::kInvalidArgument, "excluded link " + std::to_string(p) + " -> " + std::to_string(c) +
                                                        " names a scan that does not exist");
    excluded.insert({p, c});
  }
  auto usable = [&](int p, int c) { return p != c && !excluded.count({p, c}); };

  int r = -1;
  if (root) {
    r = *root;
    if (r < 0 || r >= n)
      return MakeError(ErrorCode::kInvalidArgument, "root scan " + std::to_string(r) + " does not exist (0.." +
                                                        std::to_string(n - 1) + ")");
    if (overrides[r])
      return MakeError(ErrorCode::kInvalidArgument, "scan " + std::to_string(r) + " is the root but has a parent override (" +
                                                        std::to_string(*overrides[r]) + "); drop one of the two");
  } else {
    // Tail of the heaviest off-diagonal edge (W §3.3), among scans that may be a root.
    int best = -1;
    for (int i = 0; i < n; ++i) {
      if (overrides[i]) continue;
      for (int j = 0; j < n; ++j) {
        if (!usable(i, j)) continue;
        if (r < 0 || confusion(i, j) > best) {
          best = confusion(i, j);
          r = i;
        }
      }
    }
    if (r < 0) {
      for (int i = 0; i < n && r < 0; ++i)
        if (!overrides[i]) r = i;  // a single scan, or every edge excluded
    }
    // CheckOverrides guarantees a scan without override exists (otherwise there is a cycle).
  }

  ScanOrder out;
  out.root = r;
  out.parent.assign(n, -1);
  std::vector<char> placed(n, 0);
  placed[r] = 1;
  out.order.push_back(r);

  while (true) {
    // Overrides first: a scan whose fixed parent is placed joins at once.
    bool added = false;
    for (int c = 0; c < n; ++c) {
      if (placed[c] || !overrides[c]) continue;
      const int p = *overrides[c];
      if (placed[p] && usable(p, c)) {
        placed[c] = 1;
        out.parent[c] = p;
        out.order.push_back(c);
        added = true;
      }
    }
    if (added) continue;
    // Heaviest usable edge from a placed scan to an unplaced scan without override.
    int best_p = -1, best_c = -1, best_w = 0;
    for (int c = 0; c < n; ++c) {
      if (placed[c] || overrides[c]) continue;
      for (int p = 0; p < n; ++p) {
        if (!placed[p] || !usable(p, c)) continue;
        const int w = confusion(p, c);
        if (w < min_weight) continue;
        if (best_c < 0 || w > best_w) {
          best_w = w;
          best_p = p;
          best_c = c;
        }
      }
    }
    if (best_c < 0) break;
    placed[best_c] = 1;
    out.parent[best_c] = best_p;
    out.order.push_back(best_c);
  }
  for (int i = 0; i < n; ++i)
    if (!placed[i]) out.unplaced.push_back(i);
  return out;
}

}  // namespace scanreg
