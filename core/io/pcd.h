// PCL's PCD point clouds, read and written through PCL (kept out of this header: PCL headers
// cost ~20 s of compile per file).
//
// Organized PCD (height > 1): height rows x width columns, row 0 = the cloud's first row; NaN or
// all-zero points are empty cells. Unorganized: organized by spherical projection around the
// sensor origin with a step from the point density (OrganizeCloudByDensity). The PCD viewpoint
// (sensor_origin_, sensor_orientation_) becomes world_from_scan; points stay in the sensor frame.
// Reflectance = the intensity field when present, else 0.5; colour from an rgb or rgba field. No
// angular grid for organized PCDs
// (they are often perspective cameras). The header is checked first (pcd_header.h): PCL trusts it;
// PCL's own console messages are silenced, its failures become one error naming the file.
#pragma once

#include <filesystem>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

Expected<Scan> ReadPcd(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel);

// Binary organized PCD (x y z intensity, empty cells NaN) — unorganized, every point, when the
// scan has points off its grid (list_points); the pose goes to the viewpoint
// (single precision there: PCD stores it as float). Atomic.
Status WritePcd(const std::filesystem::path& path, const Scan& scan, ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::io
