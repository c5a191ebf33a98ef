// Reading E57 (ASTM E2807) files: every 3D scan (/data3D) becomes a Scan. Structured scans
// (rowIndex/columnIndex) keep their grid: file row r, column c is Scan row r - rowMinimum,
// column c - columnMinimum. Scans without a grid are organized like PLY/PCD clouds
// (OrganizeCloudByDensity). Intensity, normalised to [0, 1] with the scan's intensityLimits (or
// the field's limits), becomes reflectance; without intensity reflectance is 0.5. colorRed/Green/Blue
// become the scan's colour, mapped to 0..255 with colorLimits (or the fields' limits). The pose
// becomes world_from_scan. Points with a non-zero cartesian/sphericalInvalidState are left out;
// a later point of a grid cell (a second return) joins the scan's list_points. A timeStamp per point
// becomes the scan's time: adjusted standard GPS time (kAdjustedGpsTime, as LAS keeps it) when the
// scan gives its acquisitionStart, the timeStamp as stored (kE57ScanSeconds) when it does not.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Scan::time_base of E57 times without a date (ASTM E2807 §8.4.3: a timeStamp counts from the
// scan's acquisitionStart, in GPS seconds, which the file need not give).
inline constexpr const char* kE57ScanSeconds = "seconds from the scan's start (E57 timeStamp, no acquisitionStart)";

// What ListE57Scans tells without decoding points.
struct E57ScanInfo {
  std::string name;          // as ReadE57 names the scan
  std::uint64_t points = 0;  // records in the file (valid or not)
  int rows = 0, cols = 0;    // from indexBounds; 0 when the scan has no grid or no bounds
  bool has_intensity = false;
  bool has_pose = false;
};

struct E57ReadOptions {
  // Scans to read, by 0-based index or by name; both empty: every scan. A selector matching no
  // scan is an error.
  std::vector<int> indices;
  std::vector<std::string> names;
};

// Reads only the header and the XML section (cheap even for large files).
Expected<std::vector<E57ScanInfo>> ListE57Scans(const std::filesystem::path& path);

// Scans are named by their E57 name; unnamed ones "<stem>_<index+1>" (or "<stem>" when the file
// holds one scan). Points far from the scanner frame's origin (> 10 km, where float loses
// millimetres) are shifted by a whole number of metres moved into world_from_scan.
Expected<std::vector<Scan>> ReadE57(const std::filesystem::path& path, const E57ReadOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::io
