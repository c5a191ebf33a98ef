// Writing merged point clouds as ASPRS LAS 1.4 (R15): point data record format 6, or 7 with colour.
//
// Encoding: X/Y/Z are int32 at a scale of 0.0001 m on every axis, relative to an offset that is the
// bounding box minimum rounded down to a whole metre, so georeferenced coordinates (hundreds of km from
// the origin) keep 0.1 mm; one axis may therefore span at most ~214 km. Every point is return 1 of 1,
// unclassified (class 0), scanner channel 0 and scan angle 0; the GPS time is the point's own where the cloud
// has times (gps_time; the global encoding's bit 0 says adjusted standard GPS time when
// adjusted_gps_time), else 0. Intensity is the reflectance
// scaled to 16 bits (a non-finite reflectance gives 0, "not recorded"); 8-bit colour is scaled to 16 bits by 256 as the
// specification asks. The point source ID is the scan index; one VLR (user ID "scanreg", record ID 1) lists
// "id<TAB>name\n" lines. The global encoding WKT bit is set (required for formats 6-10); no CRS record is written. The
// legacy point counts are zero, as the specification requires for formats 6 and above. The file is replaced atomically.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io {

struct LasCloud {
  std::vector<Eigen::Vector3d> points;  // world coordinates, metres (double)
  std::vector<float> reflectance;  // empty, or one per point, nominally [0,1] -> intensity = round(clamp(r,0,1)*65535)
  std::vector<std::array<std::uint8_t, 3>> rgb;  // empty, or one per point: then point format 7, else 6
  std::vector<std::uint16_t> source_ids;         // empty (all 0), or one per point: LAS point source ID (= scan index)
  std::vector<std::string> source_names;         // name of source id k (k = index); written as a VLR
  std::vector<double> gps_time;                  // empty (all 0), or one per point, seconds
  bool adjusted_gps_time = false;                // the times are adjusted standard GPS time (else GPS week seconds)
};

// Errors: kInvalidArgument for mismatched array sizes, non-finite points, a cloud wider than int32 at
// 0.0001 m allows on one axis, or source names that do not fit the VLR; kIoError when the file cannot
// be written (the previous file, if any, is then left untouched and no temporary file remains).
Status WriteLas(const std::filesystem::path& path, const LasCloud& cloud);

}  // namespace scanreg::io
