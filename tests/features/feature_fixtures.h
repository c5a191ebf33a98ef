// Simulated projects shared by the feature tests (built once per test binary).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <vector>

#include "core/common/progress.h"
#include "core/features/sift.h"
#include "core/geometry/scan.h"
#include "core/simulate/project_sim.h"

namespace scanreg::test {

inline std::vector<Scan> MakeProject(int stations, int cols, int rows) {
  SimulatedProjectOptions o;
  o.stations = stations;
  o.scanner.cols = cols;
  o.scanner.rows = rows;
  NullProgress progress;
  CancelToken cancel;
  auto scans = SimulateProject(o, progress, cancel);
  EXPECT_TRUE(scans.ok()) << (scans.ok() ? "" : scans.error().ToString());
  return scans.ok() ? std::move(*scans) : std::vector<Scan>();
}

// 4 stations ~5 m apart along the street, 1200 x 300 (0.3° steps).
inline const std::vector<Scan>& SmallProject() {
  static const std::vector<Scan> scans = MakeProject(4, 1200, 300);
  return scans;
}

// 2 stations ~5 m apart at W's size, 3000 x 750.
inline const std::vector<Scan>& FullSizePair() {
  static const std::vector<Scan> scans = MakeProject(2, 3000, 750);
  return scans;
}

// The world point of the valid cell nearest to (u, v); false if none within 2 pixels.
inline bool WorldPointNear(const Scan& scan, float u, float v, Eigen::Vector3d* world) {
  const int r0 = static_cast<int>(std::lround(v)), c0 = static_cast<int>(std::lround(u));
  double best = 1e9;
  for (int r = r0 - 2; r <= r0 + 2; ++r)
    for (int c = c0 - 2; c <= c0 + 2; ++c) {
      if (r < 0 || r >= scan.rows) continue;
      const int cc = (c + scan.cols) % scan.cols;
      if (!scan.IsValid(r, cc)) continue;
      const double d = (r - v) * (r - v) + (c - u) * (c - u);
      if (d < best) {
        best = d;
        *world = scan.reference_world_from_scan.value() * scan.Point(r, cc).cast<double>();
      }
    }
  return best < 1e9;
}

}  // namespace scanreg::test
