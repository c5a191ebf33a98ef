#include "core/report/project_view.h"

#include <algorithm>

namespace scanreg::report {

bool IsTreeLink(const io::LinkRecord& l) {
  return !l.loop_check && l.status != io::LinkStatus::kFailed && !l.user_rejected;
}

std::vector<int> ScanOrder(const io::Project& project) {
  std::vector<int> order;
  std::vector<bool> placed(project.scans.size(), false);
  const auto place = [&](int i) {
    if (i >= 0 && !placed[i]) order.push_back(i), placed[i] = true;
  };
  if (project.root) place(project.FindScan(*project.root));
  for (const io::LinkRecord& l : project.links)
    if (IsTreeLink(l)) place(project.FindScan(l.child));
  for (int i = 0; i < static_cast<int>(project.scans.size()); ++i) place(i);
  return order;
}

}  // namespace scanreg::report
