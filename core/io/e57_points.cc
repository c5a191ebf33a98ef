#include "core/io/e57_points.h"

#include <cmath>
#include <cstring>
#include <limits>

#include "core/io/e57_bitpack.h"

namespace scanreg::io::e57 {

namespace {

constexpr int kProgressSteps = 40;
constexpr std::uint64_t kChunk = 1 << 20;  // logical bytes read at a time
constexpr double kFarAway = 1e4;           // metres; float keeps ~1 mm up to here

enum class Role {
  kX,
  kY,
  kZ,
  kRange,
  kAzimuth,
  kElevation,
  kIntensity,
  kRed,
  kGreen,
  kBlue,
  kRow,
  kColumn,
  kInvalid,
  kReturn,
  kTime,
  kOther
};

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
      s.role = n == "cartesianX"   ? Role::kX
               : n == "cartesianY" ? Role::kY
               : n == "cartesianZ" ? Role::kZ
                                   : Role::kOther;
    } else {
      s.role = n == "sphericalRange"       ? Role::kRange
               : n == "sphericalAzimuth"   ? Role::kAzimuth
               : n == "sphericalElevation" ? Role::kElevation
                                           : Role::kOther;
    }
    if (n == "intensity") s.role = Role::kIntensity;
    if (n == "colorRed") s.role = Role::kRed;
    if (n == "colorGreen") s.role = Role::kGreen;
    if (n == "colorBlue") s.role = Role::kBlue;
    if (n == "rowIndex") s.role = Role::kRow;
    if (n == "columnIndex") s.role = Role::kColumn;
    if (n == invalid_name) s.role = Role::kInvalid;
    if (n == "returnIndex") s.role = Role::kReturn;
    if (n == "timeStamp") s.role = Role::kTime;
  }
  return streams;
}

// Whole packets from a window of the section's bytes, appended to the fields' bytestreams.
class PacketParser {
 public:
  PacketParser(std::vector<FieldStream>& streams, std::string where) : streams_(streams), where_(std::move(where)) {}

  // bytes: the window; offset: its position in the section. Returns the bytes used (whole packets).
  Expected<std::size_t> Parse(std::string_view bytes, std::uint64_t offset) {
    std::size_t pos = 0;
    while (bytes.size() - pos >= 4) {
      const char* p = bytes.data() + pos;
      const auto type = static_cast<std::uint8_t>(p[0]);
      const std::size_t length = std::size_t(LoadLe<std::uint16_t>(p + 2)) + 1;
      if (type != kDataPacket && type != kIndexPacket && type != kEmptyPacket) {
        return Bad(offset + pos, "unknown packet type " + std::to_string(type));
      }
      if (bytes.size() - pos < length) break;  // the rest comes with the next window
      if (type == kDataPacket) {
        if (Status s = DataPacket(std::string_view(p, length), offset + pos); !s) return s.error();
      }
      pos += length;
    }
    return pos;
  }

  Error Bad(std::uint64_t at, const std::string& what) const {
    return MakeError(ErrorCode::kParseError, where_ + ": packet at byte " + std::to_string(at) +
                                                 " of the points section: " + what +
                                                 "; the file is damaged, copy or export it again");
  }

 private:
  Status DataPacket(std::string_view packet, std::uint64_t at) {
    if (packet.size() < 6) return Bad(at, "a data packet shorter than its header");
    const std::size_t count = LoadLe<std::uint16_t>(packet.data() + 4);
    if (count != streams_.size()) {
      return Bad(at, "a data packet with " + std::to_string(count) + " bytestreams, but the prototype has " +
                         std::to_string(streams_.size()) + " fields");
    }
    std::size_t offset = 6 + 2 * count;
    if (offset > packet.size()) return Bad(at, "its bytestream lengths run past the packet");
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t n = LoadLe<std::uint16_t>(packet.data() + 6 + 2 * k);
      if (offset + n > packet.size()) return Bad(at, "bytestream " + std::to_string(k + 1) + " runs past the packet");
      streams_[k].bits.Append(packet.substr(offset, n));
      offset += n;
    }
    return Status::Ok();
  }

  std::vector<FieldStream>& streams_;
  std::string where_;
};

// A grid index stored as a Float; -1 (outside every grid) when it is not a whole number.
std::int64_t WholeOrMinusOne(double v) {
  return std::isfinite(v) && std::fabs(v) < 1e15 && v == std::floor(v) ? std::int64_t(v) : -1;
}

// Decodes records one at a time into `out`.
class RecordDecoder {
 public:
  RecordDecoder(std::vector<FieldStream>& streams, bool spherical, std::string where, PointRecords& out)
      : streams_(streams), spherical_(spherical), where_(std::move(where)), out_(out) {}

  // How many whole records the bytestreams hold now.
  std::uint64_t Available() const {
    std::uint64_t n = std::numeric_limits<std::uint64_t>::max();
    for (const FieldStream& s : streams_)
      if (s.field->bits > 0) n = std::min(n, s.bits.AvailableBits() / std::uint64_t(s.field->bits));
    return n;
  }

  Status Decode(std::size_t i) {
    double c[3] = {0, 0, 0};
    bool valid = true;
    for (FieldStream& s : streams_) {
      const Field& f = *s.field;
      std::uint64_t bits = 0;
      s.bits.Read(f.bits, &bits);  // Available() said the bits are there
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
        if (s.role == Role::kRow || s.role == Role::kColumn) raw = WholeOrMinusOne(value);
      } else {
        raw = static_cast<std::int64_t>(static_cast<std::uint64_t>(f.minimum) + bits);
        if (raw > f.maximum || raw < f.minimum) {
          return Bad(
              i, "'" + f.name + "' = " + std::to_string(raw) + " is above its maximum " + std::to_string(f.maximum));
        }
        value = f.type == FieldType::kScaledInteger ? double(raw) * f.scale + f.offset : double(raw);
      }
      switch (s.role) {
        case Role::kX:
        case Role::kRange:
          c[0] = value;
          break;
        case Role::kY:
        case Role::kAzimuth:
          c[1] = value;
          break;
        case Role::kZ:
        case Role::kElevation:
          c[2] = value;
          break;
        case Role::kIntensity:
          out_.intensity[i] = static_cast<float>(value);
          break;
        case Role::kRed:
        case Role::kGreen:
        case Role::kBlue:
          if (!out_.colour.empty())
            out_.colour[i][s.role == Role::kRed ? 0 : s.role == Role::kGreen ? 1 : 2] = float(value);
          break;
        case Role::kRow:
        case Role::kColumn: {
          if (raw < std::numeric_limits<std::int32_t>::min() || raw > std::numeric_limits<std::int32_t>::max()) {
            return Bad(i, "'" + f.name + "' = " + std::to_string(raw) + " is not a usable grid index");
          }
          (s.role == Role::kRow ? out_.row : out_.column)[i] = static_cast<std::int32_t>(raw);
          break;
        }
        case Role::kTime:
          out_.time[i] = value;
          break;
        case Role::kInvalid:
        case Role::kReturn:
          valid = valid && value == 0.0;
          break;
        case Role::kOther:
          break;
      }
    }
    if (spherical_) {
      const double r = c[0], az = c[1], el = c[2];
      c[0] = r * std::cos(el) * std::cos(az);
      c[1] = r * std::cos(el) * std::sin(az);
      c[2] = r * std::sin(el);
    }
    const Eigen::Vector3d p(c[0], c[1], c[2]);
    out_.valid[i] = valid;
    if (!valid) return Status::Ok();
    if (!p.allFinite() || (!out_.intensity.empty() && !std::isfinite(out_.intensity[i])) ||
        (!out_.time.empty() && !std::isfinite(out_.time[i]))) {
      return Bad(i, "a NaN or infinite coordinate, intensity or timeStamp, but the point is not marked invalid");
    }
    if (!shift_decided_) {
      shift_decided_ = true;
      if (p.cwiseAbs().maxCoeff() > kFarAway) out_.shift = p.array().round().matrix();
    }
    out_.xyz[i] = (p - out_.shift).cast<float>();
    return Status::Ok();
  }

 private:
  Error Bad(std::size_t i, const std::string& what) const {
    return MakeError(ErrorCode::kParseError,
                     where_ + ": record " + std::to_string(i + 1) + ": " + what + "; the file is damaged");
  }

  std::vector<FieldStream>& streams_;
  bool spherical_;
  std::string where_;
  PointRecords& out_;
  bool shift_decided_ = false;
};

}  // namespace

Expected<PointRecords> ReadPoints(PagedReader& file, const ScanDesc& scan, const std::string& scan_label,
                                  ProgressSink& progress, const CancelToken& cancel) {
  const std::string where = file.source() + ": " + scan_label;
  PointRecords out;
  if (scan.record_count == 0) return out;
  std::string header;
  if (Status s = file.Read(scan.points_offset, kSectionHeaderSize, "the points section of " + scan_label, &header); !s)
    return s.error();
  const std::uint64_t section_length = LoadLe<std::uint64_t>(header.data() + 8);
  const std::uint64_t data_offset = LoadLe<std::uint64_t>(header.data() + 16);
  const std::uint64_t section_start = LogicalFromPhysical(scan.points_offset);
  if (static_cast<std::uint8_t>(header[0]) != kCompressedVectorSection || section_length < kSectionHeaderSize ||
      section_length > file.logical_length() - section_start) {
    return MakeError(ErrorCode::kParseError, where + ": the points fileOffset " + std::to_string(scan.points_offset) +
                                                 " does not hold a valid CompressedVector section (wrong id or a "
                                                 "length beyond the file); the file is damaged");
  }
  const std::uint64_t data_start = LogicalFromPhysical(data_offset) - section_start;
  if (data_offset % kPageSize >= kPageData || LogicalFromPhysical(data_offset) < section_start + kSectionHeaderSize ||
      data_start >= section_length) {
    return MakeError(ErrorCode::kParseError,
                     where + ": the data offset of the points section lies outside it; the file is damaged");
  }
  std::uint64_t bits_per_record = 0;
  for (const Field& f : scan.fields) bits_per_record += std::uint64_t(f.bits);
  // A prototype of constants only (0 bits a record) stores nothing: no real scan, refuse it.
  const std::uint64_t capacity = bits_per_record == 0 ? 0 : (section_length - data_start) * 8 / bits_per_record;
  if (scan.record_count > capacity) {
    return MakeError(ErrorCode::kParseError, where + ": recordCount " + std::to_string(scan.record_count) +
                                                 " is more than the points section (" + std::to_string(section_length) +
                                                 " bytes) can hold; the file is truncated or damaged");
  }

  std::vector<FieldStream> streams = MakeStreams(scan);
  const std::size_t n = scan.record_count;
  out.xyz.resize(n);
  out.valid.resize(n);
  for (const FieldStream& s : streams) {
    if (s.role == Role::kIntensity) out.intensity.resize(n);
    if (s.role == Role::kRow) out.row.resize(n);
    if (s.role == Role::kColumn) out.column.resize(n);
    if (s.role == Role::kTime) out.time.resize(n);
  }
  if (scan.FieldIndex("colorRed") >= 0 && scan.FieldIndex("colorGreen") >= 0 && scan.FieldIndex("colorBlue") >= 0)
    out.colour.assign(n, Eigen::Vector3f::Zero());
  PacketParser parser(streams, where);
  RecordDecoder decoder(streams, scan.FieldIndex("cartesianX") < 0, where, out);
  const std::size_t report_every = std::max<std::size_t>(1, n / kProgressSteps);
  std::string window, chunk;
  std::uint64_t window_offset = data_start;  // the window's position in the section
  std::uint64_t next_read = data_start;
  std::size_t done = 0;
  while (done < n) {
    const std::uint64_t ready = std::min<std::uint64_t>(decoder.Available(), n - done);
    for (std::uint64_t k = 0; k < ready; ++k, ++done) {
      if (done % report_every == 0) {
        if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, file.source() + ": cancelled");
        progress.Report(double(done) / double(n), "reading " + scan_label);
      }
      if (Status s = decoder.Decode(done); !s) return s.error();
    }
    if (done == n) break;
    if (next_read == section_length) {
      if (window.size() >= 4) return parser.Bad(window_offset, "it runs past the end of the section");
      return MakeError(ErrorCode::kParseError, where + ": the points section ends after " + std::to_string(done) +
                                                   " of " + std::to_string(n) +
                                                   " records; the file is truncated or damaged");
    }
    const std::uint64_t take = std::min(kChunk, section_length - next_read);
    if (Status s = file.Read(PhysicalFromLogical(section_start + next_read), take,
                             "the points section of " + scan_label, &chunk);
        !s)
      return s.error();
    next_read += take;
    window += chunk;
    Expected<std::size_t> used = parser.Parse(window, window_offset);
    if (!used) return used.error();
    window.erase(0, *used);
    window_offset += *used;
  }
  progress.Report(1.0, "reading " + scan_label);
  return out;
}

}  // namespace scanreg::io::e57
