#include "core/pipeline/moving_points.h"

#include <algorithm>
#include <map>
#include <memory>
#include <numeric>

#include "core/registration/visibility.h"

namespace scanreg::pipeline {

Expected<std::vector<std::vector<std::uint32_t>>> MovingPointCells(const merge::ScanSource& scans,
                                                                   const std::vector<Eigen::Isometry3d>& poses,
                                                                   const MovingPointOptions& options,
                                                                   const CancelToken& cancel) {
  std::vector<std::vector<std::uint32_t>> cells(scans.count);
  std::vector<std::uint8_t> mask;
  // Clouds without a grid viewpoint see free space along their per-point rays: traced once each.
  std::map<int, std::shared_ptr<const RayFreeSpace>> rays;
  auto rays_of = [&](int j, const Scan& observer) -> const RayFreeSpace* {
    if (HasViewpoint(observer) || !observer.HasSensor()) return nullptr;
    auto it = rays.find(j);
    if (it == rays.end()) it = rays.emplace(j, std::make_shared<const RayFreeSpace>(observer, 0.5 * options.margin_m)).first;
    return it->second->known() ? it->second.get() : nullptr;
  };
  for (int i = 0; i < scans.count; ++i) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "merge cancelled while finding moving objects");
    auto scan = scans.get(i);
    if (!scan) return scan.error();
    mask.assign((*scan)->size(), 0);
    std::vector<int> others;
    for (int j = 0; j < scans.count; ++j)
      if (j != i) others.push_back(j);
    const Eigen::Vector3d at = poses[i].translation();
    auto distance = [&](int j) { return (poses[j].translation() - at).norm(); };
    std::stable_sort(others.begin(), others.end(), [&](int a, int b) { return distance(a) < distance(b); });
    int observed = 0;  // the nearest observers that see free space (HasViewpoint)
    for (std::size_t k = 0; k < others.size() && observed < options.observers; ++k) {
      auto observer = scans.get(others[k]);
      if (!observer) return observer.error();
      const RayFreeSpace* along = rays_of(others[k], **observer);
      if (!HasViewpoint(**observer) && !along) continue;
      ++observed;
      const Eigen::Isometry3d observer_from_scan = (*observer)->world_from_scan.inverse() * (*scan)->world_from_scan;
      MarkFreeSpacePoints(**observer, **scan, observer_from_scan, options.margin_m, &mask, along);
    }
    for (std::size_t c = 0; c < mask.size(); ++c)
      if (mask[c]) cells[i].push_back(std::uint32_t(c));
  }
  return cells;
}

}  // namespace scanreg::pipeline
