// Points on moving objects (vehicles, people) of registered scans: a point of one scan that lies in
// the free space of another scanner at the registered poses was not there when the other scan was
// taken (free-space test of core/registration/visibility.h, on every point, not sampled). The merge
// leaves them out, so the mesh has no ghosts of passing traffic; the counts are reported per scan.
#pragma once

#include <cstdint>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/merge/merge.h"

namespace scanreg::pipeline {

struct MovingPointOptions {
  double margin_m = 0.2;  // a point this much nearer than the other scanner's surface is in its free space
  int observers = 8;      // each scan is tested against this many nearest other stations
};

// Per scan (its world_from_scan the registered pose), its cells whose point lies in the free space
// of one of its nearest other scans, ascending. Scans without a panoramic grid (no angles) can be
// tested but do not observe, unless they give each point's sensor position (free space along
// those rays, ray_free_space.h). Scan by scan, for scans read when needed (issue 13: a project larger
// than memory): scan i and its observers are asked of `scans` in turn (poses[i]: scan i's pose, to
// choose the observers before reading them). Errors: a scan that cannot be read; cancelled
// (kCancelled).
Expected<std::vector<std::vector<std::uint32_t>>> MovingPointCells(const merge::ScanSource& scans,
                                                                   const std::vector<Eigen::Isometry3d>& poses,
                                                                   const MovingPointOptions& options,
                                                                   const CancelToken& cancel);

}  // namespace scanreg::pipeline
