// Station poses as CSV, for spreadsheets and survey software:
//   scan,x_m,y_m,z_m,heading_deg,pitch_deg,roll_deg,status
// one row per scan (status: NamedPose::status; an "unregistered" row has empty numbers and is not
// read back; files without the status column are read too); the position is the scanner origin in the world
// (world_from_scan's translation) and the angles are world_from_scan's rotation R = Rz(heading) Ry(pitch) Rx(roll)
// (core/geometry/pose_angles.h), in degrees. Numbers are written so that they read back exactly.
#pragma once

#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/io/pose_file.h"

namespace scanreg::io {

// Atomic. Scan names holding a comma or a quote are quoted ("a,b" -> "\"a,b\"").
Status WritePosesCsv(const std::filesystem::path& path, const std::vector<NamedPose>& poses);

// Reads what WritePosesCsv writes (the header line is required); errors name the file and line.
Expected<std::vector<NamedPose>> ReadPosesCsv(const std::filesystem::path& path);

}  // namespace scanreg::io
