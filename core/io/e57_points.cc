#include "core/io/e57_points.h"

#include <cmath>
#include <cstring>

#include "core/io/e57_bitpack.h"

namespace scanreg::io::e57 {

namespace {

constexpr int kProgressSteps = 40;

enum class Role { kX, kY, kZ, kRange, kAzimuth, kElevation, kIntensity, kRow, kColumn, kInvalid, kReturn, kOther };

std::uint64_t LoadU64(const char* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= std::uint64_t(static_cast<unsigned char>(p[i])) << (8 * i);
  return v;
}

std::uint16_t LoadU16(const char* p) {
  return static_cast<std::uint16_t>(static_cast<unsigned char>(p[0]) | (static_cast<unsigned char>(p[1]) << 8));
}

// A grid index stored as a Float; -1 (outside every grid) when it is not a whole number.
std::int64_t WholeOrMinusOne(double v) {
  return std::isfinite(v) && std::fabs(v) < 1e15 && v == std::floor(v) ? std::int64_t(v) : -1;
}

struct FieldStream {
  const Field* field = nullptr;
  Role role = Role::kOther;
  BitReader bits;
};

std::vector<FieldStream> MakeStreams(const ScanDesc& scan) {
  const bool cartesian = scan.FieldIndex("cartesianX") >= 0;
  const std::string invalid_name = cartesian ? "cartesianInvalidState" : "sphericalInvalidState";
  std::vector<FieldStream> streams(scan.fields.size());
  for (std::size_t i = 0; i < scan.fields.size(); ++i) {
    const std::string& n = scan.fields[i].name;
    FieldStream& s = streams[i];
    s.field = &scan.fields[i];
    if (cartesian) {
      s.role = n == "cartesianX" ? Role::kX : n == "cartesianY" ? Role::kY : n == "cartesianZ" ? Role::kZ : Role::kOther;
    } else {
      s.role = n == "sphericalRange"       ? Role::kRange
               : n == "sphericalAzimuth"   ? Role::kAzimuth
               : n == "sphericalElevation" ? Role::kElevation
                                           : Role::kOther;
    }
    if (n == "intensity") s.role = Role::kIntensity;
    if (n == "rowIndex") s.role = Role::kRow;
    if (n == "columnIndex") s.role = Role::kColumn;
    if (n == invalid_name) s.role = Role::kInvalid;
    if (n == "returnIndex") s.role = Role::kReturn;
  }
  return streams;
}

// Splits the section's data packets into the bytestreams of each field.
Status CollectBytestreams(const std::string& section, std::uint64_t data_start, std::vector<FieldStream>& streams,
                          const std::string& where) {
  auto bad = [&](std::uint64_t pos, const std::string& what) {
    return MakeError(ErrorCode::kParseError, where + ": packet at byte " + std::to_string(pos) +
                                                 " of the points section: " + what +
                                                 "; the file is damaged, copy or export it again");
  };
  std::uint64_t pos = data_start;
  while (section.size() - pos >= 4) {
    const char* p = section.data() + pos;
    const auto type = static_cast<std::uint8_t>(p[0]);
    const std::uint64_t length = std::uint64_t(LoadU16(p + 2)) + 1;
    if (pos + length > section.size()) return bad(pos, "its length runs past the end of the section");
    if (type == kDataPacket) {
      if (length < 6) return bad(pos, "a data packet shorter than its header");
      const std::size_t count = LoadU16(p + 4);
      if (count != streams.size()) {
        return bad(pos, "a data packet with " + std::to_string(count) + " bytestreams, but the prototype has " +
                            std::to_string(streams.size()) + " fields");
      }
      std::uint64_t offset = 6 + 2 * count;
      if (offset > length) return bad(pos, "its bytestream lengths run past the packet");
      for (std::size_t k = 0; k < count; ++k) {
        const std::uint64_t n = LoadU16(p + 6 + 2 * k);
        if (offset + n > length) return bad(pos, "bytestream " + std::to_string(k + 1) + " runs past the packet");
        streams[k].bits.AddSegment(std::string_view(p + offset, n));
        offset += n;
      }
    } else if (type != kIndexPacket && type != kEmptyPacket) {
      return bad(pos, "unknown packet type " + std::to_string(type));
    }
    pos += length;
  }
  return Status::Ok();
}

}  // namespace

Expected<PointRecords> ReadPoints(PagedReader& file, const ScanDesc& scan, const std::string& scan_label,
                                  ProgressSink& progress, const CancelToken& cancel) {
  const std::string where = file.source() + ": " + scan_label;
  PointRecords out;
  if (scan.record_count == 0) return out;
  std::string header;
  if (Status s = file.Read(scan.points_offset, kSectionHeaderSize, "the points section of " + scan_label, &header); !s)
    return s.error();
  const std::uint64_t section_length = LoadU64(header.data() + 8);
  const std::uint64_t data_offset = LoadU64(header.data() + 16);
  if (static_cast<std::uint8_t>(header[0]) != kCompressedVectorSection || section_length < kSectionHeaderSize) {
    return MakeError(ErrorCode::kParseError, where + ": the points fileOffset does not point at a CompressedVector "
                                                     "section; the file is damaged");
  }
  const std::uint64_t section_start = LogicalFromPhysical(scan.points_offset);
  const std::uint64_t data_start = LogicalFromPhysical(data_offset) - section_start;
  if (data_offset % kPageSize >= kPageData || LogicalFromPhysical(data_offset) < section_start + kSectionHeaderSize ||
      data_start >= section_length) {
    return MakeError(ErrorCode::kParseError,
                     where + ": the data offset of the points section lies outside it; the file is damaged");
  }
  std::uint64_t bits_per_record = 0;
  for (const Field& f : scan.fields) bits_per_record += std::uint64_t(f.bits);
  const std::uint64_t capacity =
      bits_per_record == 0 ? std::uint64_t(1) << 32 : (section_length - data_start) * 8 / bits_per_record;
  if (scan.record_count > capacity) {
    return MakeError(ErrorCode::kParseError,
                     where + ": recordCount " + std::to_string(scan.record_count) + " is more than the points section (" +
                         std::to_string(section_length) + " bytes) can hold; the file is truncated or damaged");
  }
  std::string section;
  if (Status s = file.Read(scan.points_offset, section_length, "the points section of " + scan_label, &section); !s)
    return s.error();
  std::vector<FieldStream> streams = MakeStreams(scan);
  if (Status s = CollectBytestreams(section, data_start, streams, where); !s) return s.error();

  const std::size_t n = scan.record_count;
  const bool spherical = scan.FieldIndex("cartesianX") < 0;
  out.xyz.resize(n);
  out.valid.assign(n, 1);
  for (const FieldStream& s : streams) {
    if (s.role == Role::kIntensity) out.intensity.resize(n);
    if (s.role == Role::kRow) out.row.resize(n);
    if (s.role == Role::kColumn) out.column.resize(n);
    if (s.role == Role::kReturn) out.first_return.resize(n);
  }
  const std::size_t report_every = std::max<std::size_t>(1, n / kProgressSteps);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % report_every == 0) {
      if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, file.source() + ": cancelled");
      progress.Report(double(i) / double(n), "reading " + scan_label);
    }
    double c[3] = {0, 0, 0};
    for (FieldStream& s : streams) {
      const Field& f = *s.field;
      std::uint64_t bits = 0;
      if (!s.bits.Read(f.bits, &bits)) {
        return MakeError(ErrorCode::kParseError, where + ": the bytestream of '" + f.name + "' ends after " +
                                                     std::to_string(i) + " of " + std::to_string(n) +
                                                     " records; the file is truncated or damaged");
      }
      double value = 0;
      std::int64_t raw = 0;
      if (f.type == FieldType::kFloat) {
        if (f.single_precision) {
          const auto u = static_cast<std::uint32_t>(bits);
          float v;
          std::memcpy(&v, &u, 4);
          value = v;
        } else {
          std::memcpy(&value, &bits, 8);
        }
      } else {
        raw = static_cast<std::int64_t>(static_cast<std::uint64_t>(f.minimum) + bits);
        if (raw > f.maximum || raw < f.minimum) {
          return MakeError(ErrorCode::kParseError, where + ": record " + std::to_string(i + 1) + ": '" + f.name +
                                                       "' = " + std::to_string(raw) + " is above its maximum " +
                                                       std::to_string(f.maximum) + "; the file is damaged");
        }
        value = f.type == FieldType::kScaledInteger ? double(raw) * f.scale + f.offset : double(raw);
      }
      switch (s.role) {
        case Role::kX:
        case Role::kRange: c[0] = value; break;
        case Role::kY:
        case Role::kAzimuth: c[1] = value; break;
        case Role::kZ:
        case Role::kElevation: c[2] = value; break;
        case Role::kIntensity: out.intensity[i] = static_cast<float>(value); break;
        case Role::kRow: out.row[i] = f.type == FieldType::kFloat ? WholeOrMinusOne(value) : raw; break;
        case Role::kColumn: out.column[i] = f.type == FieldType::kFloat ? WholeOrMinusOne(value) : raw; break;
        case Role::kInvalid: out.valid[i] = value == 0.0; break;
        case Role::kReturn: out.first_return[i] = value == 0.0; break;
        case Role::kOther: break;
      }
    }
    if (spherical) {
      const double r = c[0], az = c[1], el = c[2];
      c[0] = r * std::cos(el) * std::cos(az);
      c[1] = r * std::cos(el) * std::sin(az);
      c[2] = r * std::sin(el);
    }
    out.xyz[i] = Eigen::Vector3d(c[0], c[1], c[2]);
    if (out.valid[i] && !(std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]) &&
                          (out.intensity.empty() || std::isfinite(out.intensity[i])))) {
      return MakeError(ErrorCode::kParseError, where + ": record " + std::to_string(i + 1) +
                                                   " has a NaN or infinite coordinate or intensity but is not marked "
                                                   "invalid; the exporter wrote bad data");
    }
  }
  progress.Report(1.0, "reading " + scan_label);
  return out;
}

}  // namespace scanreg::io::e57
