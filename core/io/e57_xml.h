// The E57 XML section read into plain descriptions of the 3D scans (/data3D): name, pose, grid
// bounds, intensity limits and the points CompressedVector (section offset, record count,
// prototype). ASTM E2807 §8.4 and §9.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io::e57 {

enum class FieldType { kFloat, kScaledInteger, kInteger };

// One field of a points prototype, e.g. cartesianX as a ScaledInteger.
struct Field {
  std::string name;
  FieldType type = FieldType::kFloat;
  bool single_precision = false;  // Float: 4 bytes instead of 8
  std::int64_t minimum = 0;       // (Scaled)Integer raw limits
  std::int64_t maximum = 0;
  double scale = 1.0;  // ScaledInteger: value = raw * scale + offset
  double offset = 0.0;
  std::optional<double> float_minimum, float_maximum;  // Float: declared limits, if any
  int bits = 0;                                        // bits per value in the bytestream

  // The smallest and largest value the field can hold (for intensity without intensityLimits).
  std::optional<std::pair<double, double>> ValueLimits() const;
};

struct IndexBounds {
  std::int64_t row_minimum = 0, row_maximum = 0;
  std::int64_t column_minimum = 0, column_maximum = 0;
};

struct ScanDesc {
  std::string name;  // may be empty
  std::string guid;
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  bool has_pose = false;
  std::uint64_t points_offset = 0;  // physical offset of the CompressedVector section
  std::uint64_t record_count = 0;
  std::vector<Field> fields;
  std::optional<IndexBounds> index_bounds;
  std::optional<std::pair<double, double>> intensity_limits;
  std::optional<std::pair<double, double>> colour_limits;  // colorLimits: colorRedMinimum, colorRedMaximum
  // acquisitionStart/dateTimeValue: GPS seconds (since GPS time was zero) that the points' timeStamp
  // counts from (ASTM E2807 §8.4.3).
  std::optional<double> acquisition_start;

  // Index of the named field in `fields`, or -1.
  int FieldIndex(std::string_view field_name) const;
  bool HasGrid() const { return FieldIndex("rowIndex") >= 0 && FieldIndex("columnIndex") >= 0; }
};

// Parses the XML text; `source` (the file name) opens every error message.
Expected<std::vector<ScanDesc>> ParseE57Xml(std::string_view xml, const std::string& source);

}  // namespace scanreg::io::e57
