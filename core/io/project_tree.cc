#include "core/io/project_tree.h"

#include <algorithm>

namespace scanreg::io {

bool IsTreeLink(const LinkRecord& l) { return !l.loop_check && l.status != LinkStatus::kFailed && !l.user_rejected; }

std::vector<int> OrderedScanIndices(const Project& project) {
  std::vector<int> order;
  std::vector<bool> placed(project.scans.size(), false);
  const auto place = [&](int i) {
    if (i >= 0 && !placed[i]) order.push_back(i), placed[i] = true;
  };
  if (project.root) place(project.FindScan(*project.root));
  for (const LinkRecord& l : project.links)
    if (IsTreeLink(l)) place(project.FindScan(l.child));
  for (int i = 0; i < static_cast<int>(project.scans.size()); ++i) place(i);
  return order;
}

std::vector<int> ScansRegisteredThrough(const Project& project, int root) {
  std::vector<int> out{root};
  for (std::size_t k = 0; k < out.size(); ++k) {
    const std::string& name = project.scans[out[k]].name;
    for (const LinkRecord& l : project.links) {
      if (!IsTreeLink(l) || l.parent != name) continue;
      const int c = project.FindScan(l.child);
      if (c >= 0 && std::find(out.begin(), out.end(), c) == out.end()) out.push_back(c);
    }
  }
  return out;
}

std::vector<bool> RestsOnHandPlacement(const Project& project) {
  std::vector<bool> out(project.scans.size(), false);
  for (std::size_t m = 0; m < project.scans.size(); ++m) {
    if (!project.scans[m].registered || !project.scans[m].manual_pose) continue;
    for (int i : ScansRegisteredThrough(project, static_cast<int>(m))) out[i] = project.scans[i].registered;
  }
  return out;
}

}  // namespace scanreg::io
