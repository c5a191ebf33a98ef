// Test helper: an organized scan made by casting the rays of a panoramic scanner into a closed
// box-shaped room with a few box-shaped blocks (no dependency on core/simulate).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/geometry/scan.h"

namespace scanreg::testing {

struct AxisBox {
  Eigen::Vector3d min, max;
};

// A 12 x 8 x 3 m room with four blocks that break its symmetries.
AxisBox DefaultRoom();
std::vector<AxisBox> DefaultBlocks();

// rows x cols panorama (elevation -60..+60°, azimuth over the full turn), scanner at
// world_from_scan; points in the scanner frame; every ray hits (closed room). range_sigma_m adds
// Gaussian range noise along each ray (seeded, reproducible).
Scan CastRoomScan(const Eigen::Isometry3d& world_from_scan, int rows, int cols, const AxisBox& room,
                  const std::vector<AxisBox>& blocks, double range_sigma_m = 0.0, unsigned seed = 1);

// A station in the room: 1.5 m above the floor at (x, y), turned heading_deg about the vertical.
Eigen::Isometry3d RoomStation(double x, double y, double heading_deg);

// pose moved by deg about a random axis and mm in a random direction (in its own frame; seeded).
Eigen::Isometry3d MovedPose(const Eigen::Isometry3d& pose, double mm, double deg, unsigned seed);

}  // namespace scanreg::testing
