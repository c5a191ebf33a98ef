#include "core/io/scan_cache.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <optional>

#include "core/common/atomic_file.h"
#include "core/common/hash.h"
#include "core/common/log.h"
#include "core/io/scan_file.h"
#include "core/io/text_parse.h"

namespace scanreg::io {
namespace {

constexpr char kMagic[8] = {'S', 'R', 'G', 'S', 'C', 'A', 'N', '\0'};
constexpr std::uint32_t kVersion = 7;  // 3: grid_from_file; 4: list points, single_viewpoint; 5: colour; 6: time; 7: sensor
constexpr std::size_t kFixedHeader = 8 + 4 + 4 + 8;
constexpr std::uint32_t kMaxScans = 1u << 20;
// The header: the fixed part, n + 1 offsets, its checksum.
std::size_t HeaderBytes(std::uint32_t n) { return kFixedHeader + 8 * (std::size_t(n) + 1) + 8; }

template <typename T>
void Put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}
void PutBytes(std::string& out, const void* data, std::size_t bytes) {
  out.append(static_cast<const char*>(data), bytes);
}

// Reads from the entry's bytes up to `end`, refusing to run past it.
struct Reader {
  const std::string& in;
  std::size_t pos = 0;
  std::size_t end = in.size();
  bool ok = true;
  bool Bytes(void* out, std::size_t n) {
    if (!ok || pos > end || n > end - pos) return ok = false;
    std::memcpy(out, in.data() + pos, n);
    pos += n;
    return true;
  }
  template <typename T>
  T Get() {
    T v{};
    Bytes(&v, sizeof(T));
    return v;
  }
};

std::uint64_t Checksum(const char* data, std::size_t bytes) {
  Hasher h(0x5CA4CAC4EULL);
  h.Add(data, bytes);
  return h.Digest();
}

void PutPose(std::string& out, const Eigen::Isometry3d& pose) { PutBytes(out, pose.matrix().data(), 16 * sizeof(double)); }

}  // namespace

Expected<std::uint64_t> SourceFileKey(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return MakeError(ErrorCode::kNotFound, "cannot read '" + file.string() + "'");
  Hasher h(kVersion);
  std::vector<char> buffer(1 << 22);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const std::streamsize got = in.gcount();
    if (got > 0) h.Add(buffer.data(), static_cast<std::size_t>(got));
  }
  if (in.bad()) return MakeError(ErrorCode::kIoError, "reading '" + file.string() + "' failed");
  return h.Digest();
}

Expected<std::uint64_t> MemoisedSourceFileKey(const std::filesystem::path& file,
                                              const std::filesystem::path& cache_dir) {
  std::error_code ec;
  const std::string path = std::filesystem::absolute(file).lexically_normal().string();
  const auto size = std::filesystem::file_size(file, ec);
  const auto time = std::filesystem::last_write_time(file, ec);
  if (ec || cache_dir.empty() || path.find('\n') != std::string::npos) return SourceFileKey(file);
  const long long mtime = static_cast<long long>(time.time_since_epoch().count());
  char stat[64];
  std::snprintf(stat, sizeof stat, " %llu %lld ", static_cast<unsigned long long>(size), mtime);
  const std::filesystem::path memo = cache_dir / "source-keys";
  // Lines "<16 hex key> <size> <mtime> <path>"; the last line for a path wins.
  std::optional<std::uint64_t> known;
  std::ifstream in(memo);
  for (std::string line; std::getline(in, line);) {
    if (line.size() < 17 || line.compare(16, std::string::npos, std::string(stat) + path) != 0) continue;
    unsigned long long key = 0;
    if (std::sscanf(line.c_str(), "%16llx", &key) == 1) known = key;
  }
  if (known) return *known;
  Expected<std::uint64_t> key = SourceFileKey(file);
  if (!key) return key;
  const auto age = std::filesystem::file_time_type::clock::now() - time;
  if (age > std::chrono::seconds(2)) {
    std::filesystem::create_directories(cache_dir, ec);
    char hex[20];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(*key));
    // One short line appended at once: concurrent writers (pair jobs) do not interleave.
    if (std::FILE* out = std::fopen(memo.c_str(), "a")) {
      const std::string line = hex + std::string(stat) + path + "\n";
      std::fwrite(line.data(), 1, line.size(), out);
      std::fclose(out);
    }
  }
  return key;
}

namespace {

// "scans_<8 hex of the absolute path>_": the prefix of every entry of one source file.
std::string EntryPrefix(const std::filesystem::path& file) {
  const std::string path = std::filesystem::absolute(file).lexically_normal().string();
  Hasher h(0xF11EULL);
  h.Add(path.data(), path.size());
  char prefix[32];
  std::snprintf(prefix, sizeof(prefix), "scans_%08llx_", static_cast<unsigned long long>(h.Digest() & 0xffffffffULL));
  return prefix;
}

}  // namespace

std::filesystem::path ScanCachePath(const std::filesystem::path& cache_dir, const std::filesystem::path& file,
                                    std::uint64_t key) {
  char name[32];
  std::snprintf(name, sizeof(name), "%016llx.scan", static_cast<unsigned long long>(key));
  return cache_dir / (EntryPrefix(file) + name);
}

namespace {

Error Bad(const std::string& why) { return MakeError(ErrorCode::kParseError, "scan cache entry: " + why); }

// One scan's record, its checksum last.
void PutRecord(std::string& out, const Scan& s) {
  const std::size_t begin = out.size();
  Put(out, static_cast<std::uint32_t>(s.name.size()));
  PutBytes(out, s.name.data(), s.name.size());
  Put(out, static_cast<std::int32_t>(s.rows));
  Put(out, static_cast<std::int32_t>(s.cols));
  PutPose(out, s.world_from_scan);
  Put(out, static_cast<std::uint8_t>(s.reference_world_from_scan.has_value()));
  if (s.reference_world_from_scan) PutPose(out, *s.reference_world_from_scan);
  Put(out, static_cast<std::uint8_t>(s.grid_from_file));
  Put(out, static_cast<std::uint32_t>(s.angles.azimuth.size()));
  PutBytes(out, s.angles.azimuth.data(), s.angles.azimuth.size() * sizeof(float));
  Put(out, static_cast<std::uint32_t>(s.angles.elevation.size()));
  PutBytes(out, s.angles.elevation.data(), s.angles.elevation.size() * sizeof(float));
  PutBytes(out, s.points.data(), s.points.size() * sizeof(Eigen::Vector3f));
  PutBytes(out, s.reflectance.data(), s.reflectance.size() * sizeof(float));
  PutBytes(out, s.valid.data(), s.valid.size());
  Put(out, static_cast<std::uint8_t>(s.single_viewpoint));
  Put(out, static_cast<std::uint64_t>(s.list_points.size()));
  PutBytes(out, s.list_points.data(), s.list_points.size() * sizeof(Eigen::Vector3f));
  PutBytes(out, s.list_reflectance.data(), s.list_reflectance.size() * sizeof(float));
  Put(out, static_cast<std::uint8_t>(s.HasColour()));
  if (s.HasColour()) {
    PutBytes(out, s.colour.data(), s.colour.size() * sizeof(Rgb));
    PutBytes(out, s.list_colour.data(), s.list_colour.size() * sizeof(Rgb));
  }
  Put(out, static_cast<std::uint8_t>(s.HasTime()));
  if (s.HasTime()) {
    Put(out, static_cast<std::uint32_t>(s.time_base.size()));
    PutBytes(out, s.time_base.data(), s.time_base.size());
    PutBytes(out, s.time.data(), s.time.size() * sizeof(double));
    PutBytes(out, s.list_time.data(), s.list_time.size() * sizeof(double));
  }
  Put(out, static_cast<std::uint8_t>(s.HasSensor()));
  if (s.HasSensor()) {
    PutBytes(out, s.sensor.data(), s.sensor.size() * sizeof(Eigen::Vector3f));
    PutBytes(out, s.list_sensor.data(), s.list_sensor.size() * sizeof(Eigen::Vector3f));
  }
  Put(out, Checksum(out.data() + begin, out.size() - begin));
}

std::size_t RecordBytes(const Scan& s) {
  return 4 + s.name.size() + 4 + 4 + 128 + 1 + (s.reference_world_from_scan ? 128 : 0) + 1 + 4 +
         4 * s.angles.azimuth.size() + 4 + 4 * s.angles.elevation.size() + 17 * s.size() + 1 + 8 + 16 * s.list_points.size() + 1 +
         (s.HasColour() ? 3 * (s.size() + s.list_points.size()) : 0) + 1 +
         (s.HasTime() ? 4 + s.time_base.size() + 8 * (s.size() + s.list_points.size()) : 0) + 1 +
         (s.HasSensor() ? 12 * (s.size() + s.list_points.size()) : 0) + 8;
}

// The record in bytes [begin, end).
Expected<Scan> ParseRecord(const std::string& bytes, std::size_t begin, std::size_t end) {
  if (end < begin + 8 || end > bytes.size()) return Bad("truncated");
  std::uint64_t stored = 0;
  std::memcpy(&stored, bytes.data() + end - 8, 8);
  if (stored != Checksum(bytes.data() + begin, end - begin - 8)) return Bad("checksum mismatch (corrupt)");
  Reader r{bytes, begin, end - 8};
  const std::uint32_t name_bytes = r.Get<std::uint32_t>();
  if (!r.ok || name_bytes > 4096) return Bad("truncated or corrupt scan name");
  std::string name(name_bytes, '\0');
  r.Bytes(name.data(), name_bytes);
  const std::int32_t rows = r.Get<std::int32_t>(), cols = r.Get<std::int32_t>();
  // Sizes are checked against the bytes of the record before anything is allocated.
  const std::uint64_t cells = static_cast<std::uint64_t>(std::max(rows, 0)) * static_cast<std::uint64_t>(std::max(cols, 0));
  if (!r.ok || rows <= 0 || cols <= 0 || cells * 17 > end - begin) return Bad("truncated or corrupt grid size");
  Scan s(std::move(name), rows, cols);
  Eigen::Matrix4d m;
  r.Bytes(m.data(), 16 * sizeof(double));
  s.world_from_scan.matrix() = m;
  if (r.Get<std::uint8_t>()) {
    r.Bytes(m.data(), 16 * sizeof(double));
    Eigen::Isometry3d ref;
    ref.matrix() = m;
    s.reference_world_from_scan = ref;
  }
  s.grid_from_file = r.Get<std::uint8_t>() != 0;
  const std::uint32_t az = r.Get<std::uint32_t>();
  if (!r.ok || (az != 0 && az != static_cast<std::uint32_t>(cols))) return Bad("corrupt angles");
  s.angles.azimuth.resize(az);
  r.Bytes(s.angles.azimuth.data(), az * sizeof(float));
  const std::uint32_t el = r.Get<std::uint32_t>();
  if (!r.ok || (el != 0 && el != static_cast<std::uint32_t>(rows))) return Bad("corrupt angles");
  s.angles.elevation.resize(el);
  r.Bytes(s.angles.elevation.data(), el * sizeof(float));
  r.Bytes(s.points.data(), cells * sizeof(Eigen::Vector3f));
  r.Bytes(s.reflectance.data(), cells * sizeof(float));
  r.Bytes(s.valid.data(), cells);
  s.single_viewpoint = r.Get<std::uint8_t>() != 0;
  const std::uint64_t listed = r.Get<std::uint64_t>();
  if (!r.ok || listed > (end - begin) / 16) return Bad("truncated or corrupt list of points");
  s.list_points.resize(listed);
  s.list_reflectance.resize(listed);
  r.Bytes(s.list_points.data(), listed * sizeof(Eigen::Vector3f));
  r.Bytes(s.list_reflectance.data(), listed * sizeof(float));
  if (r.Get<std::uint8_t>() != 0) {
    if (!r.ok || (cells + listed) * sizeof(Rgb) > end - r.pos) return Bad("truncated or corrupt colours");
    s.AddColour();
    r.Bytes(s.colour.data(), cells * sizeof(Rgb));
    r.Bytes(s.list_colour.data(), listed * sizeof(Rgb));
  }
  if (r.Get<std::uint8_t>() != 0) {
    const std::uint32_t base_bytes = r.Get<std::uint32_t>();
    if (!r.ok || base_bytes > 4096) return Bad("truncated or corrupt time base");
    s.time_base.assign(base_bytes, '\0');
    r.Bytes(s.time_base.data(), base_bytes);
    if (!r.ok || (cells + listed) * sizeof(double) > end - r.pos) return Bad("truncated or corrupt times");
    s.AddTime();
    r.Bytes(s.time.data(), cells * sizeof(double));
    r.Bytes(s.list_time.data(), listed * sizeof(double));
  }
  if (r.Get<std::uint8_t>() != 0) {
    if (!r.ok || (cells + listed) * sizeof(Eigen::Vector3f) > end - r.pos) return Bad("truncated or corrupt sensor positions");
    s.AddSensor();
    r.Bytes(s.sensor.data(), cells * sizeof(Eigen::Vector3f));
    r.Bytes(s.list_sensor.data(), listed * sizeof(Eigen::Vector3f));
  }
  if (!r.ok) return Bad("truncated");
  if (r.pos != end - 8) return Bad("trailing bytes in a scan's record");
  return s;
}

// The records' offsets from the header (`bytes` holds at least the header), checked against the
// entry's size.
Expected<std::vector<std::uint64_t>> ParseHeader(const std::string& bytes, std::uint64_t key, std::uint64_t entry_bytes) {
  if (bytes.size() < kFixedHeader || std::memcmp(bytes.data(), kMagic, 8) != 0) return Bad("not a scan cache entry");
  Reader r{bytes, 8};
  if (r.Get<std::uint32_t>() != kVersion) return Bad("written by another version");
  const std::uint32_t n = r.Get<std::uint32_t>();
  if (r.Get<std::uint64_t>() != key) return Bad("the entry of another file");
  if (n > kMaxScans || HeaderBytes(n) > entry_bytes || HeaderBytes(n) > bytes.size()) return Bad("truncated header");
  std::vector<std::uint64_t> offsets(n + 1);
  r.Bytes(offsets.data(), offsets.size() * 8);
  const std::uint64_t stored = r.Get<std::uint64_t>();
  if (!r.ok || stored != Checksum(bytes.data(), HeaderBytes(n) - 8)) return Bad("checksum mismatch in the header (corrupt)");
  if (offsets.front() != HeaderBytes(n) || offsets.back() != entry_bytes) return Bad("truncated or corrupt offsets");
  for (std::uint32_t k = 0; k < n; ++k)
    if (offsets[k + 1] < offsets[k] + 8) return Bad("corrupt offsets");
  return offsets;
}

}  // namespace

std::string SerializeScanCache(const std::vector<Scan>& scans, std::uint64_t key) {
  const std::uint32_t n = static_cast<std::uint32_t>(scans.size());
  std::uint64_t at = HeaderBytes(n);
  std::vector<std::uint64_t> offsets{at};
  for (const Scan& s : scans) offsets.push_back(at += RecordBytes(s));
  std::string out;
  out.reserve(at);
  PutBytes(out, kMagic, 8);
  Put(out, kVersion);
  Put(out, n);
  Put(out, key);
  PutBytes(out, offsets.data(), offsets.size() * 8);
  Put(out, Checksum(out.data(), out.size()));
  for (const Scan& s : scans) PutRecord(out, s);
  return out;
}

Expected<std::vector<Scan>> ParseScanCache(const std::string& bytes, std::uint64_t key) {
  Expected<std::vector<std::uint64_t>> offsets = ParseHeader(bytes, key, bytes.size());
  if (!offsets) return offsets.error();
  std::vector<Scan> scans;
  for (std::size_t k = 0; k + 1 < offsets->size(); ++k) {
    Expected<Scan> s = ParseRecord(bytes, (*offsets)[k], (*offsets)[k + 1]);
    if (!s) return s.error();
    scans.push_back(std::move(*s));
  }
  return scans;
}

Expected<Scan> ReadScanCacheRecord(const std::filesystem::path& entry, std::uint64_t key, int index,
                                   int* scans_in_entry) {
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(entry, ec);
  if (ec) return MakeError(ErrorCode::kIoError, "scan cache entry: cannot read its size: " + ec.message());
  std::ifstream in(entry, std::ios::binary);
  std::string header(kFixedHeader, '\0');
  if (!in.read(header.data(), std::streamsize(header.size()))) return Bad("truncated header");
  std::uint32_t n = 0;
  std::memcpy(&n, header.data() + 12, 4);
  if (n > kMaxScans || HeaderBytes(n) > size) return Bad("truncated header");
  header.resize(HeaderBytes(n));
  if (!in.read(header.data() + kFixedHeader, std::streamsize(header.size() - kFixedHeader))) return Bad("truncated header");
  Expected<std::vector<std::uint64_t>> offsets = ParseHeader(header, key, size);
  if (!offsets) return offsets.error();
  if (scans_in_entry) *scans_in_entry = int(n);
  if (index < 0 || index >= int(n)) return MakeError(ErrorCode::kInvalidArgument, "scan cache entry: no scan number " + std::to_string(index + 1));
  const std::uint64_t begin = (*offsets)[index], end = (*offsets)[index + 1];
  std::string record(end - begin, '\0');
  in.seekg(std::streamoff(begin));
  if (!in.read(record.data(), std::streamsize(record.size()))) return Bad("truncated");
  return ParseRecord(record, 0, record.size());
}

Expected<std::vector<Scan>> ReadScanFileCached(const std::filesystem::path& file,
                                               const std::filesystem::path& cache_dir, ProgressSink& progress,
                                               const CancelToken& cancel, bool* from_cache, int only) {
  if (from_cache) *from_cache = false;
  if (cache_dir.empty()) return ReadScanFile(file, progress, cancel);
  Expected<std::uint64_t> key = MemoisedSourceFileKey(file, cache_dir);
  if (!key) return ReadScanFile(file, progress, cancel);  // the reader names the problem
  const std::filesystem::path entry = ScanCachePath(cache_dir, file, *key);
  std::error_code ec;
  if (only >= 0 && std::filesystem::is_regular_file(entry, ec)) {  // that scan's record alone
    int n = 0;
    Expected<Scan> one = ReadScanCacheRecord(entry, *key, only, &n);
    if (one || (one.error().code == ErrorCode::kInvalidArgument && n > 0)) {
      if (from_cache) *from_cache = true;
      std::vector<Scan> scans(n);
      if (one) scans[only] = std::move(*one);
      progress.Report(1.0, "read a scan of " + file.filename().string() + " from the scan cache");
      return scans;
    }
    LogWarning(entry.string() + ": " + one.error().message + "; re-reading " + file.string());
  } else if (std::filesystem::is_regular_file(entry, ec)) {
    Expected<std::string> bytes = ReadWholeFile(entry);  // one block read, not byte by byte
    Expected<std::vector<Scan>> cached = bytes ? ParseScanCache(*bytes, *key) : Expected<std::vector<Scan>>(bytes.error());
    if (cached) {
      if (from_cache) *from_cache = true;
      progress.Report(1.0, "read " + file.filename().string() + " from the scan cache");
      return cached;
    }
    LogWarning(entry.string() + ": " + cached.error().message + "; re-reading " + file.string());
  }
  Expected<std::vector<Scan>> read = ReadScanFile(file, progress, cancel);
  if (!read) return read;
  std::filesystem::create_directories(cache_dir, ec);
  AtomicFile out(entry);
  Status s = out.Open();
  if (s) s = out.Write(SerializeScanCache(*read, *key));
  if (s) s = out.Commit();
  if (!s) {
    LogWarning("scan cache: cannot write " + entry.string() + ": " + s.error().message);
    return read;
  }
  // The file's superseded entries (its earlier contents) go.
  const std::string prefix = EntryPrefix(file);
  for (const auto& e : std::filesystem::directory_iterator(cache_dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path() != entry && name.size() > 5 && name.substr(name.size() - 5) == ".scan")
      std::filesystem::remove(e.path(), ec);
  }
  return read;
}

}  // namespace scanreg::io
