#include "core/pipeline/moving_points.h"

#include <algorithm>
#include <numeric>

#include "core/registration/visibility.h"

namespace scanreg::pipeline {

std::vector<std::vector<std::uint8_t>> MovingPointMasks(const std::vector<const Scan*>& scans,
                                                        const MovingPointOptions& options, const CancelToken& cancel) {
  std::vector<std::vector<std::uint8_t>> masks(scans.size());
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (cancel.IsCancelled()) break;
    const Scan& scan = *scans[i];
    masks[i].assign(scan.size(), 0);
    std::vector<std::size_t> others;
    for (std::size_t j = 0; j < scans.size(); ++j)
      if (j != i && !scans[j]->angles.empty()) others.push_back(j);
    const Eigen::Vector3d at = scan.world_from_scan.translation();
    auto distance = [&](std::size_t j) { return (scans[j]->world_from_scan.translation() - at).norm(); };
    std::sort(others.begin(), others.end(), [&](std::size_t a, std::size_t b) { return distance(a) < distance(b); });
    if (others.size() > static_cast<std::size_t>(std::max(options.observers, 0))) others.resize(options.observers);
    for (std::size_t j : others) {
      const Eigen::Isometry3d observer_from_scan = scans[j]->world_from_scan.inverse() * scan.world_from_scan;
      MarkFreeSpacePoints(*scans[j], scan, observer_from_scan, options.margin_m, &masks[i]);
    }
  }
  return masks;
}

}  // namespace scanreg::pipeline
