#include "core/io/las_reader.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <new>

#include "core/io/organize_default.h"

namespace scanreg::io {
namespace {

// Offsets in the public header block (LAS 1.4 R15, table 3; the same in 1.0-1.3 up to 227).
constexpr int kHeaderSize12 = 227;  // the whole 1.0-1.2 header; 1.3 adds 8 bytes, 1.4 148 more
constexpr int kHeaderSize14 = 375;

template <typename T>
T Get(const std::vector<char>& b, std::size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);  // LAS is little-endian, as every platform we build for
  return v;
}

std::string Trimmed(const std::vector<char>& b, std::size_t at, std::size_t n) {
  std::string s(b.data() + at, n);
  s = s.substr(0, s.find('\0'));
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

}  // namespace

int LasMinimumRecordLength(int point_format) {
  static constexpr std::array<int, 11> kLength = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
  return point_format >= 0 && point_format <= 10 ? kLength[point_format] : 0;
}

int LasGpsTimeOffset(int point_format) {
  if (point_format == 1 || (point_format >= 3 && point_format <= 5)) return 20;
  return point_format >= 6 && point_format <= 10 ? 22 : -1;
}

int LasRgbOffset(int point_format) {
  switch (point_format) {
    case 2:
      return 20;
    case 3:
    case 5:
      return 28;
    case 7:
    case 8:
    case 10:
      return 30;
    default:
      return -1;
  }
}

Expected<LasPoints> ReadLasPoints(const std::filesystem::path& path, ProgressSink& progress,
                                  const CancelToken& cancel) {
  const std::string name = path.string();
  const auto bad = [&](const std::string& what) { return MakeError(ErrorCode::kParseError, name + ": " + what); };
  std::error_code ec;
  const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec) return MakeError(ErrorCode::kIoError, name + ": cannot read the file size: " + ec.message());
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(ErrorCode::kIoError, name + ": cannot open the file; check that it exists and is readable");
  if (file_size < static_cast<std::uintmax_t>(kHeaderSize12)) {
    return bad("only " + std::to_string(file_size) +
               " bytes: shorter than a LAS header (227 bytes); the file is "
               "truncated or not LAS");
  }
  std::vector<char> h(kHeaderSize14, 0);
  in.read(h.data(), static_cast<std::streamsize>(std::min<std::uintmax_t>(file_size, kHeaderSize14)));
  if (!in && !in.eof()) return MakeError(ErrorCode::kIoError, name + ": cannot read the header");
  in.clear();
  if (std::memcmp(h.data(), "LASF", 4) != 0) return bad("does not start with \"LASF\": not a LAS file");

  LasPoints out;
  out.version_major = static_cast<unsigned char>(h[24]);
  out.version_minor = static_cast<unsigned char>(h[25]);
  if (out.version_major != 1 || out.version_minor > 4) {
    return MakeError(ErrorCode::kUnsupported, name + ": LAS version " + std::to_string(out.version_major) + "." +
                                                  std::to_string(out.version_minor) + " (supported: 1.0 to 1.4)");
  }
  out.generating_software = Trimmed(h, 58, 32);
  out.global_encoding = Get<std::uint16_t>(h, 6);
  const int header_size = Get<std::uint16_t>(h, 94);
  const std::uint32_t point_offset = Get<std::uint32_t>(h, 96);
  const int format_byte = static_cast<unsigned char>(h[104]);
  out.record_length = Get<std::uint16_t>(h, 105);
  std::uint64_t count = Get<std::uint32_t>(h, 107);
  const int needed_header = out.version_minor >= 4 ? kHeaderSize14 : kHeaderSize12;
  if (header_size < needed_header) {
    return bad("the header says it is " + std::to_string(header_size) + " bytes, but a LAS 1." +
               std::to_string(out.version_minor) + " header has at least " + std::to_string(needed_header));
  }
  if (static_cast<std::uintmax_t>(header_size) > file_size) {
    return bad("the header says it is " + std::to_string(header_size) + " bytes, more than the whole file (" +
               std::to_string(file_size) + " bytes): truncated");
  }
  if (point_offset < static_cast<std::uint32_t>(header_size)) {
    return bad("the offset to the point data (" + std::to_string(point_offset) + ") lies inside the " +
               std::to_string(header_size) + "-byte header; the header is damaged");
  }
  if (out.version_minor >= 4) {
    const std::uint64_t count64 = Get<std::uint64_t>(h, 247);
    if (count64 != 0 || count == 0) count = count64;
  }
  if (format_byte & 0xC0) {
    return MakeError(ErrorCode::kUnsupported, name + ": the points are LASzip-compressed (point format byte " +
                                                  std::to_string(format_byte) + "); decompress the file first, e.g. " +
                                                  "`laszip -i FILE -o FILE.las` or `pdal translate FILE FILE.las`");
  }
  out.point_format = format_byte;
  const int minimum = LasMinimumRecordLength(out.point_format);
  if (minimum == 0) {
    return MakeError(ErrorCode::kUnsupported,
                     name + ": point data record format " + std::to_string(out.point_format) + " (supported: 0 to 10)");
  }
  if (out.record_length < minimum) {
    return bad("point records of " + std::to_string(out.record_length) + " bytes, but format " +
               std::to_string(out.point_format) + " needs at least " + std::to_string(minimum));
  }
  for (int a = 0; a < 3; ++a) {
    out.scale[a] = Get<double>(h, 131 + 8 * a);
    out.offset[a] = Get<double>(h, 155 + 8 * a);
    out.header_max[a] = Get<double>(h, 179 + 16 * a);
    out.header_min[a] = Get<double>(h, 187 + 16 * a);
    if (!std::isfinite(out.scale[a]) || out.scale[a] == 0.0 || !std::isfinite(out.offset[a])) {
      return bad(std::string("the ") + "xyz"[a] +
                 " scale factor or offset is zero or not a number; the header is "
                 "damaged");
    }
  }
  if (point_offset > file_size) {
    return bad("the point data should start at byte " + std::to_string(point_offset) + ", beyond the end of the " +
               std::to_string(file_size) + "-byte file: truncated");
  }
  // The point records end where extended VLRs (1.4) or internal waveform data (1.3+) begin.
  std::uint64_t end = file_size;
  if (out.version_minor >= 3) {
    const std::uint64_t waveform = Get<std::uint64_t>(h, 227);
    if (waveform > point_offset && waveform < end) end = waveform;
  }
  if (out.version_minor >= 4) {
    const std::uint64_t evlr = Get<std::uint64_t>(h, 235);
    if (evlr > point_offset && evlr < end) end = evlr;
  }
  const std::uint64_t room = (end - point_offset) / static_cast<std::uint64_t>(out.record_length);
  if (count == 0 && room > 0) {  // a writer that never filled in the count: not an empty file
    return bad("the header says it holds 0 points, but " + std::to_string(room) + " complete " +
               std::to_string(out.record_length) +
               "-byte records follow it: the header is damaged (rewrite the file, e.g. with pdal translate or "
               "las2las)");
  }
  if (count > room) {
    return bad("the header promises " + std::to_string(count) + " points, but the file holds only " +
               std::to_string(room) + " complete " + std::to_string(out.record_length) +
               "-byte records: truncated (copy it again)");
  }

  const int gps_at = LasGpsTimeOffset(out.point_format), rgb_at = LasRgbOffset(out.point_format);
  try {
    out.xyz.resize(count);
    out.intensity.resize(count);
    out.gps_time.resize(gps_at >= 0 ? count : 0);
    out.rgb.resize(rgb_at >= 0 ? count : 0);
  } catch (const std::bad_alloc&) {
    return MakeError(ErrorCode::kIoError, name + ": " + std::to_string(count) +
                                              " points do not fit in memory; split the file (e.g. with las2las or pdal "
                                              "split) and import the parts");
  }
  in.seekg(point_offset);
  // Read in chunks of at most 16 MB whatever the record length (up to 64 KB a record).
  const std::uint64_t chunk = std::max<std::uint64_t>(1, (16u << 20) / static_cast<std::uint64_t>(out.record_length));
  std::vector<char> buffer;
  const std::string stage = "reading " + path.filename().string();
  for (std::uint64_t first = 0; first < count; first += chunk) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, name + ": cancelled");
    const std::uint64_t n = std::min(chunk, count - first);
    buffer.resize(n * out.record_length);
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    if (!in) {
      return MakeError(ErrorCode::kIoError, name + ": cannot read point " + std::to_string(first) + " onwards");
    }
    for (std::uint64_t k = 0; k < n; ++k) {
      const std::size_t at = k * out.record_length;
      const Eigen::Vector3d raw(Get<std::int32_t>(buffer, at), Get<std::int32_t>(buffer, at + 4),
                                Get<std::int32_t>(buffer, at + 8));
      out.xyz[first + k] = raw.cwiseProduct(out.scale) + out.offset;
      if (!out.xyz[first + k].allFinite()) {
        return bad("point " + std::to_string(first + k) +
                   " is not a finite number after scale and offset; the "
                   "header's scale factors are damaged");
      }
      out.intensity[first + k] = Get<std::uint16_t>(buffer, at + 12);
      if (gps_at >= 0) {
        out.gps_time[first + k] = Get<double>(buffer, at + gps_at);
        if (!std::isfinite(out.gps_time[first + k])) {
          return bad("point " + std::to_string(first + k) + " has a GPS time that is not a finite number; the "
                     "record is damaged");
        }
      }
      if (rgb_at >= 0)
        for (int c = 0; c < 3; ++c) out.rgb[first + k][c] = Get<std::uint16_t>(buffer, at + rgb_at + 2 * c);
    }
    progress.Report(double(first + n) / double(count), stage);
  }
  return out;
}

Expected<Scan> ReadLas(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel) {
  Expected<LasPoints> las = ReadLasPoints(path, progress, cancel);
  if (!las) return las.error();
  if (las->xyz.empty()) {
    Scan empty(path.stem().string(), 0, 0);
    return empty;
  }
  // The local frame's origin: the median point, per axis (in double).
  Eigen::Vector3d centre;
  std::vector<double> axis(las->xyz.size());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t k = 0; k < axis.size(); ++k) axis[k] = las->xyz[k][a];
    std::nth_element(axis.begin(), axis.begin() + axis.size() / 2, axis.end());
    centre[a] = axis[axis.size() / 2];
  }
  std::vector<Eigen::Vector3f> points(las->xyz.size());
  for (std::size_t k = 0; k < points.size(); ++k) points[k] = (las->xyz[k] - centre).cast<float>();
  const std::uint16_t brightest = *std::max_element(las->intensity.begin(), las->intensity.end());
  const float full_scale = brightest <= 255 ? 255.0f : 65535.0f;
  std::vector<float> reflectance(las->intensity.size(), 0.5f);  // no intensity at all: 0.5, as other readers
  if (brightest > 0)
    for (std::size_t k = 0; k < reflectance.size(); ++k) reflectance[k] = las->intensity[k] / full_scale;
  las->xyz = {};
  // 16 bits a channel, by the specification; files whose channels never exceed 255 hold 8-bit values.
  // The high byte serves writers that scale 8 bits by 256 and those that scale by 257.
  std::vector<Rgb> colour(las->rgb.size());
  std::uint16_t strongest = 0;
  for (const auto& c : las->rgb) strongest = std::max({strongest, c[0], c[1], c[2]});
  const int shift = strongest <= 255 ? 0 : 8;
  for (std::size_t k = 0; k < colour.size(); ++k)
    for (int c = 0; c < 3; ++c) colour[k][c] = static_cast<std::uint8_t>(las->rgb[k][c] >> shift);
  las->rgb = {};
  Expected<Scan> scan =
      OrganizeCloudByDensity(points, reflectance, path.stem().string(), path.string(), colour, las->gps_time);
  if (!scan) return scan.error();
  if (scan->HasTime()) scan->time_base = (las->global_encoding & 1u) ? kAdjustedGpsTime : kGpsWeekSeconds;
  scan->world_from_scan = Eigen::Isometry3d(Eigen::Translation3d(centre));
  return scan;
}

}  // namespace scanreg::io
