#include "core/io/las_writer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <limits>
#include <string_view>

#include "core/common/atomic_file.h"

namespace scanreg::io {

namespace {

// Sizes and codes from the LAS 1.4 R15 specification (public header block, VLR header, PDRF 6/7).
constexpr double kScale = 0.0001;               // metres per integer step, all axes
constexpr double kStepsPerMetre = 10000.0;      // 1 / kScale, exact
constexpr std::uint16_t kHeaderSize = 375;      // LAS 1.4 public header block
constexpr std::uint32_t kVlrHeaderSize = 54;    // reserved, user ID, record ID, length, description
constexpr std::size_t kMaxVlrPayload = 65535;   // "Record Length After Header" is an unsigned short
constexpr std::uint16_t kAdjustedGpsBit = 1u;  // global encoding: GPS times are adjusted standard GPS time
constexpr std::uint16_t kWktBit = 1u << 4;      // global encoding: CRS (if any) is WKT; required for PDRF 6-10
constexpr std::uint8_t kReturnOneOfOne = 0x11;  // return number (bits 0-3) = 1, number of returns (bits 4-7) = 1
constexpr std::size_t kPointsPerChunk = 1 << 16;

void PutU8(std::string& out, std::uint8_t v) { out.push_back(static_cast<char>(v)); }

// Explicit little-endian stores: the file layout does not depend on the host.
template <typename UInt>
void PutLe(std::string& out, UInt v) {
  for (std::size_t i = 0; i < sizeof(UInt); ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}

void PutI32(std::string& out, std::int32_t v) { PutLe(out, static_cast<std::uint32_t>(v)); }

void PutF64(std::string& out, double v) {
  std::uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  PutLe(out, bits);
}

// A fixed-width char[] field: the text, then nulls. Callers pass text that fits.
void PutText(std::string& out, std::string_view text, std::size_t width) {
  out.append(text.substr(0, width));
  out.append(width - std::min(width, text.size()), '\0');
}

Error Invalid(const std::filesystem::path& path, const std::string& what) {
  return MakeError(ErrorCode::kInvalidArgument, "cannot write LAS file '" + path.string() + "': " + what);
}

Status CheckSizes(const std::filesystem::path& path, const LasCloud& cloud) {
  const std::size_t n = cloud.points.size();
  const auto check = [&](std::size_t size, const char* what) -> Status {
    if (size == 0 || size == n) return Status::Ok();
    return Invalid(path, "the cloud has " + std::to_string(n) + " points but " + std::to_string(size) + " " + what +
                             "; give one per point or none");
  };
  if (Status s = check(cloud.reflectance.size(), "reflectance values"); !s) return s;
  if (Status s = check(cloud.rgb.size(), "colours"); !s) return s;
  if (Status s = check(cloud.gps_time.size(), "GPS times"); !s) return s;
  for (std::size_t i = 0; i < cloud.gps_time.size(); ++i)
    if (!std::isfinite(cloud.gps_time[i]))
      return Invalid(path, "point " + std::to_string(i) + " has a GPS time that is not a finite number");
  return check(cloud.source_ids.size(), "source IDs");
}

// The integer grid: coordinate = steps * kScale + offset.
struct Grid {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  std::array<std::int32_t, 3> lo{0, 0, 0}, hi{0, 0, 0};  // bounds in steps

  std::int32_t Steps(double value, int axis) const {
    return static_cast<std::int32_t>(std::llround((value - offset[axis]) * kStepsPerMetre));
  }
};

// Checks every point is finite and that the cloud fits int32 steps on each axis. Quantization is
// monotonic, so the quantized bounds are the quantized extremes.
Expected<Grid> MakeGrid(const std::filesystem::path& path, const std::vector<Eigen::Vector3d>& points) {
  Grid grid;
  if (points.empty()) return grid;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    if (!p.allFinite()) {
      char buf[160];
      std::snprintf(buf, sizeof buf, "point %zu is not finite (%g, %g, %g); drop such points before exporting", i,
                    p.x(), p.y(), p.z());
      return Invalid(path, buf);
    }
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  static const char* const kAxis[3] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    grid.offset[a] = std::floor(lo[a]);
    const double top = (hi[a] - grid.offset[a]) * kStepsPerMetre;
    if (!(top < static_cast<double>(std::numeric_limits<std::int32_t>::max()))) {
      char buf[320];
      std::snprintf(buf, sizeof buf,
                    "the cloud spans %.3f km along %s (%.3f to %.3f m), more than the %.1f km a LAS file with "
                    "0.1 mm steps can hold on one axis; export fewer or nearer scans, or check the poses",
                    (hi[a] - lo[a]) / 1000.0, kAxis[a], lo[a], hi[a],
                    std::numeric_limits<std::int32_t>::max() * kScale / 1000.0);
      return Invalid(path, buf);
    }
    grid.lo[a] = grid.Steps(lo[a], a);
    grid.hi[a] = grid.Steps(hi[a], a);
  }
  return grid;
}

// The VLR payload: "id<TAB>name\n" per source.
Expected<std::string> NamesPayload(const std::filesystem::path& path, const std::vector<std::string>& names) {
  if (names.size() > std::size_t{std::numeric_limits<std::uint16_t>::max()} + 1)
    return Invalid(path,
                   std::to_string(names.size()) + " scan names given, but a point source ID holds at most 65,536");
  std::string text;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (names[k].find_first_of("\t\r\n") != std::string::npos)
      return Invalid(path, "the name of scan " + std::to_string(k) + " contains a tab or line break; rename the scan");
    text += std::to_string(k) + '\t' + names[k] + '\n';
  }
  if (text.size() > kMaxVlrPayload)
    return Invalid(path, "the scan names take " + std::to_string(text.size()) +
                             " bytes, more than the 65,535 a LAS variable length record holds; shorten them");
  return text;
}

std::string HeaderBlock(const LasCloud& cloud, const Grid& grid, std::uint32_t point_offset, std::uint8_t format,
                        std::uint16_t record_length) {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);

  std::string out;
  out.reserve(kHeaderSize);
  out += "LASF";
  PutLe<std::uint16_t>(out, 0);        // file source ID: unassigned (an aggregate of scans)
  PutLe<std::uint16_t>(out, kWktBit | (cloud.adjusted_gps_time ? kAdjustedGpsBit : 0));  // global encoding
  out.append(16, '\0');                // project ID (GUID): unused
  PutU8(out, 1);                       // version 1.4
  PutU8(out, 4);
  PutText(out, "scanreg export", 32);                                      // system identifier
  PutText(out, "scanreg", 32);                                             // generating software
  PutLe<std::uint16_t>(out, static_cast<std::uint16_t>(utc.tm_yday + 1));  // GMT day, 1 January = 1
  PutLe<std::uint16_t>(out, static_cast<std::uint16_t>(utc.tm_year + 1900));
  PutLe<std::uint16_t>(out, kHeaderSize);
  PutLe<std::uint32_t>(out, point_offset);
  PutLe<std::uint32_t>(out, 1);  // number of VLRs
  PutU8(out, format);
  PutLe<std::uint16_t>(out, record_length);
  // Legacy point count and legacy points by return [5]: must be zero for point formats 6 and above.
  out.append(4 + 5 * 4, '\0');
  for (int a = 0; a < 3; ++a) PutF64(out, kScale);
  for (int a = 0; a < 3; ++a) PutF64(out, grid.offset[a]);
  for (int a = 0; a < 3; ++a) {  // max then min, per axis
    PutF64(out, grid.hi[a] * kScale + grid.offset[a]);
    PutF64(out, grid.lo[a] * kScale + grid.offset[a]);
  }
  PutLe<std::uint64_t>(out, 0);  // start of waveform data packet record: none
  PutLe<std::uint64_t>(out, 0);  // start of first EVLR: none
  PutLe<std::uint32_t>(out, 0);  // number of EVLRs
  const std::uint64_t n = cloud.points.size();
  PutLe<std::uint64_t>(out, n);  // number of point records
  PutLe<std::uint64_t>(out, n);  // number of points by return [15]: all are return 1
  out.append(14 * 8, '\0');
  return out;
}

std::string VlrHeader(std::size_t payload_size) {
  std::string out;
  PutLe<std::uint16_t>(out, 0);  // reserved
  PutText(out, "scanreg", 16);   // user ID
  PutLe<std::uint16_t>(out, 1);  // record ID
  PutLe<std::uint16_t>(out, static_cast<std::uint16_t>(payload_size));
  PutText(out, "scan names by point source ID", 32);
  return out;
}

std::uint16_t Intensity(float reflectance) {
  if (std::isnan(reflectance)) return 0;
  return static_cast<std::uint16_t>(std::lround(std::clamp(double(reflectance), 0.0, 1.0) * 65535.0));
}

void PutPoint(std::string& out, const LasCloud& cloud, const Grid& grid, std::size_t i) {
  const Eigen::Vector3d& p = cloud.points[i];
  for (int a = 0; a < 3; ++a) PutI32(out, grid.Steps(p[a], a));
  PutLe<std::uint16_t>(out, cloud.reflectance.empty() ? 0 : Intensity(cloud.reflectance[i]));
  PutU8(out, kReturnOneOfOne);
  PutU8(out, 0);                 // classification flags, scanner channel 0, scan direction, edge of flight line
  PutU8(out, 0);                 // classification: created, never classified
  PutU8(out, 0);                 // user data
  PutLe<std::uint16_t>(out, 0);  // scan angle (int16, 0.006 deg steps): not recorded
  PutLe<std::uint16_t>(out, cloud.source_ids.empty() ? 0 : cloud.source_ids[i]);
  PutF64(out, cloud.gps_time.empty() ? 0.0 : cloud.gps_time[i]);  // 0: not recorded
  if (!cloud.rgb.empty())
    for (std::uint8_t c : cloud.rgb[i]) PutLe<std::uint16_t>(out, static_cast<std::uint16_t>(c * 256));
}

}  // namespace

Status WriteLas(const std::filesystem::path& path, const LasCloud& cloud) {
  if (Status s = CheckSizes(path, cloud); !s) return s;
  Expected<Grid> grid = MakeGrid(path, cloud.points);
  if (!grid) return grid.error();
  Expected<std::string> names = NamesPayload(path, cloud.source_names);
  if (!names) return names.error();

  const bool colour = !cloud.rgb.empty();
  const std::uint8_t format = colour ? 7 : 6;
  const std::uint16_t record_length = colour ? 36 : 30;
  const auto point_offset = static_cast<std::uint32_t>(kHeaderSize + kVlrHeaderSize + names->size());

  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  std::string head = HeaderBlock(cloud, *grid, point_offset, format, record_length);
  head += VlrHeader(names->size());
  head += *names;
  if (Status s = file.Write(head); !s) return s;

  std::string chunk;
  chunk.reserve(kPointsPerChunk * record_length);
  for (std::size_t begin = 0; begin < cloud.points.size(); begin += kPointsPerChunk) {
    const std::size_t end = std::min(cloud.points.size(), begin + kPointsPerChunk);
    chunk.clear();
    for (std::size_t i = begin; i < end; ++i) PutPoint(chunk, cloud, *grid, i);
    if (Status s = file.Write(chunk); !s) return s;
  }
  return file.Commit();
}

}  // namespace scanreg::io
