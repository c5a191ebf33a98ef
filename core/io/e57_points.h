// Decoding the points of one E57 scan: the CompressedVector binary section (ASTM E2807 §9.8:
// section header, data packets of bytestreams, index and empty packets) into plain arrays.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/io/e57_pages.h"
#include "core/io/e57_xml.h"

namespace scanreg::io::e57 {

constexpr std::size_t kSectionHeaderSize = 32;
constexpr std::uint8_t kCompressedVectorSection = 1;
constexpr std::uint8_t kIndexPacket = 0, kDataPacket = 1, kEmptyPacket = 2;
constexpr std::size_t kMaxPacketSize = 65536;

// One entry per record, in file order. Spherical coordinates are converted to cartesian.
// Coordinates far from the origin (> 10 km, where float loses millimetres) are stored minus
// `shift`, a whole number of metres taken from the first valid point (ReadE57 moves it into
// world_from_scan).
struct PointRecords {
  std::vector<Eigen::Vector3f> xyz;  // scanner frame minus shift, metres
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  // 0 where the invalid state says there are no coordinates, or for second and later returns.
  std::vector<std::uint8_t> valid;
  std::vector<float> intensity;           // as stored; empty when the scan has none
  std::vector<Eigen::Vector3f> colour;    // colorRed, colorGreen, colorBlue as stored; empty without all three
  std::vector<std::int32_t> row, column;  // rowIndex / columnIndex; empty when the scan has no grid
  std::vector<double> time;               // timeStamp, seconds as stored; empty when the scan has none
};

// Reads the section in chunks: memory holds the records, not the compressed section.
// `scan_label` ("scan 2 ('pumpA')") names the scan in error messages.
Expected<PointRecords> ReadPoints(PagedReader& file, const ScanDesc& scan, const std::string& scan_label,
                                  ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::io::e57
