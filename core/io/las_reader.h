// ASPRS LAS input, versions 1.0-1.4, point data record formats 0-10 (issue 34, item 4): what
// mobile mappers, handheld SLAM scanners and other programs export. Uncompressed only: a file whose
// format byte carries LASzip's compression bits gets an error that says how to decompress it (an
// uncompressed file named .laz is read as what it is).
//
// Coordinates are X * scale + offset in double precision, as the specification defines them, so a
// cloud in UTM (hundreds of kilometres from the origin) keeps its millimetres. Records longer than
// their format's minimum (extra bytes) are read and the extra bytes skipped. The point count is
// the 64-bit one of LAS 1.4 when set, else the legacy 32-bit one. Every promise of the header is
// checked against the file before anything is allocated: a truncated file names how many complete
// points it holds and how many the header promises.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

struct LasPoints {
  int version_major = 1, version_minor = 0;
  int point_format = 0;             // 0-10
  int record_length = 0;            // bytes per point record (>= the format's minimum)
  std::string generating_software;  // the header's own words
  Eigen::Vector3d scale = Eigen::Vector3d::Ones(), offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d header_min = Eigen::Vector3d::Zero(), header_max = Eigen::Vector3d::Zero();  // as written
  std::vector<Eigen::Vector3d> xyz;     // world coordinates, metres (or the file's units)
  std::vector<std::uint16_t> intensity;  // one per point, as stored
  // Per point where the format has them (empty otherwise), as stored: GPS time (formats 1 and 3-10;
  // GPS week seconds or adjusted standard GPS time, as the header's global encoding says) and red,
  // green, blue (formats 2, 3, 5, 7, 8, 10; 16 bits a channel). A Scan keeps the colour (8 bits a
  // channel: the high byte, or the value itself when no channel exceeds 255) and the time, with its
  // base (Scan::time_base: kGpsWeekSeconds or kAdjustedGpsTime).
  std::vector<double> gps_time;
  std::uint16_t global_encoding = 0;  // bit 0: the GPS times are adjusted standard GPS time
  std::vector<std::array<std::uint16_t, 3>> rgb;
};

// Scan::time_base of times read from LAS, by the header's global encoding bit 0 (LAS 1.4 R15, table 4).
inline constexpr const char* kGpsWeekSeconds = "GPS week seconds";
inline constexpr const char* kAdjustedGpsTime = "adjusted standard GPS time (GPS seconds - 1e9)";
inline constexpr double kAdjustedGpsOffset = 1e9;  // GPS seconds = adjusted standard GPS time + this

// The minimum record length of a point data format (0-10); 0 for an unknown format.
int LasMinimumRecordLength(int point_format);
// Where a format's GPS time (double) and RGB (3 x uint16) start in its records (LAS 1.4 R15, tables
// 7-17); -1 when the format has none.
int LasGpsTimeOffset(int point_format);
int LasRgbOffset(int point_format);

Expected<LasPoints> ReadLasPoints(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel);

// One scan from a LAS file: its points in a local frame centred on the median point (the pose
// holds that centre in double, so world coordinates are kept exactly), intensity as reflectance
// (divided by 255 when no value exceeds 255 — 8-bit sensors written into the 16-bit field — else by
// 65535; 0.5 when every intensity is 0), organized around that centre as any unstructured cloud is
// (organize_default.h: points that share a grid cell with a nearer one stay in the scan's list,
// and a cloud seen from several places — mobile, airborne, merged — is marked so).
Expected<Scan> ReadLas(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::io
