// The real multi-view sets of tests/data/realdata that have reference poses (SOURCES.md), loaded
// as scans with reference_world_from_scan set, with the tolerances the trust protocol of issue 33
// judges a registration of them by.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg::test {

struct RealSet {
  std::string name;
  std::vector<Scan> scans;  // reference_world_from_scan set on every scan
  // A pair of registered scans within these of the reference is right: the reference poses' own
  // precision + 2 x the scanner's noise (issue 33).
  double within_m = 0.0, within_deg = 0.0;
  // Beyond these a registered scan is wrong: 5 % of the scene's extent (at most 1 cm for scenes
  // over 20 cm) / 2 deg, or the reference's own precision when that is larger.
  double wrong_m = 0.0, wrong_deg = 2.0;
};

// TUM RGB-D fr3_cabinet keyframes 30-41 (tum_fr3_cabinet/): one 480 x 640 perspective grid per
// depth image (camera frame: x right, y down, z forward; metres), the reflectance the grey of the
// registered colour image; the reference the motion-capture camera poses.
Expected<RealSet> LoadTumCabinet(const std::filesystem::path& realdata);

}  // namespace scanreg::test
