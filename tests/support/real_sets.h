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
  // For a reference that drifts along a sequence (KITTI's GPS/INS): more per scan between the two.
  double within_m_per_step = 0.0;
  double WithinM(std::size_t i, std::size_t j) const {
    const std::size_t steps = i > j ? i - j : j - i;
    return within_m + within_m_per_step * double(steps > 0 ? steps - 1 : 0);
  }
  // Beyond these a registered scan is wrong: 5 % of the scene's extent (at most 1 cm for scenes
  // over 20 cm) / 2 deg, or the reference's own precision when that is larger.
  double wrong_m = 0.0, wrong_deg = 2.0;
};

// TUM RGB-D fr3_cabinet keyframes 30-41 (tum_fr3_cabinet/): one 480 x 640 perspective grid per
// depth image (camera frame: x right, y down, z forward; metres), the reflectance the grey of the
// registered colour image; the reference the motion-capture camera poses.
Expected<RealSet> LoadTumCabinet(const std::filesystem::path& realdata);

// Four consecutive Velodyne HDL-64E scans of KITTI odometry sequence 00 (kitti00_velodyne/, points
// beyond 40 m left out), read by ReadPly as a user's import would; the reference the GPS/INS poses
// through KITTI's calibration, which put the scans 0.13-0.17 m apart along the way the car drives
// from where the lidar data put them (SOURCES.md), so they judge gross errors only.
Expected<RealSet> LoadKittiVelodyne(const std::filesystem::path& realdata);

// Three stop-and-go scans of a tilted 2D laser on a robot in a corridor (3dtk_robot_scans/, the
// example scans of 3DTK), read by ReadPly; the reference the 3DTK authors' own registration, good
// to about 5 cm / 1 deg (SOURCES.md).
Expected<RealSet> Load3dtkCorridor(const std::filesystem::path& realdata);

}  // namespace scanreg::test
