// Points on moving objects (vehicles, people) of registered scans: a point of one scan that lies in
// the free space of another scanner at the registered poses was not there when the other scan was
// taken (free-space test of core/registration/visibility.h, on every point, not sampled). The merge
// leaves them out, so the mesh has no ghosts of passing traffic; the counts are reported per scan.
#pragma once

#include <cstdint>
#include <vector>

#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::pipeline {

struct MovingPointOptions {
  double margin_m = 0.2;  // a point this much nearer than the other scanner's surface is in its free space
  int observers = 8;      // each scan is tested against this many nearest other stations
};

// For each scan (world_from_scan = its registered pose) a mask over its cells: 1 where the point lies
// in the free space of one of its nearest other scans. Scans without a panoramic grid (no angles)
// can be tested but do not observe. Cancelled: the masks computed so far (the rest empty).
std::vector<std::vector<std::uint8_t>> MovingPointMasks(const std::vector<const Scan*>& scans,
                                                        const MovingPointOptions& options, const CancelToken& cancel);

}  // namespace scanreg::pipeline
