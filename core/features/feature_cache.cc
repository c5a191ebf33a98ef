#include "core/features/feature_cache.h"

#include <cstdio>
#include <cstring>
#include <fstream>
#include <opencv2/core/version.hpp>
#include <sstream>
#include <string>
#include <system_error>

#include "core/common/atomic_file.h"
#include "core/common/hash.h"
#include "core/common/log.h"

namespace scanreg {
namespace {

constexpr char kMagic[8] = {'S', 'R', 'G', 'F', 'E', 'A', 'T', '\0'};
constexpr std::uint32_t kFormatVersion = 1;
// Bump when DetectFeatures changes its output for the same options (invalidates old entries).
constexpr std::uint64_t kDetectorVersion = 1;
constexpr std::size_t kHeaderBytes = 8 + 4 + 4 + 8 + 4 + 4 + 8;
constexpr int kKeypointFloats = 5;

std::uint64_t PayloadChecksum(const char* data, std::size_t bytes) {
  Hasher h(0x5EEDF00DULL);
  h.Add(data, bytes);
  return h.Digest();
}

template <typename T>
void Put(std::string& out, const T& value) {
  out.append(reinterpret_cast<const char*>(&value), sizeof(T));
}
template <typename T>
T Get(const std::string& in, std::size_t& pos) {
  T value;
  std::memcpy(&value, in.data() + pos, sizeof(T));
  pos += sizeof(T);
  return value;
}

std::string Serialize(const ScanFeatures& f, std::uint64_t key) {
  const std::uint64_t n = f.keypoints.size();
  std::string out;
  out.reserve(kHeaderBytes + n * (kKeypointFloats + kSiftDescriptorSize) * 4 + 8);
  out.append(kMagic, 8);
  Put(out, kFormatVersion);
  Put(out, static_cast<std::uint32_t>(kSiftDescriptorSize));
  Put(out, key);
  Put(out, static_cast<std::int32_t>(f.rows));
  Put(out, static_cast<std::int32_t>(f.cols));
  Put(out, n);
  for (const Keypoint& k : f.keypoints) {
    const float values[kKeypointFloats] = {k.u, k.v, k.size, k.angle, k.response};
    out.append(reinterpret_cast<const char*>(values), sizeof(values));
  }
  out.append(reinterpret_cast<const char*>(f.descriptors.data()), f.descriptors.size() * sizeof(float));
  Put(out, PayloadChecksum(out.data() + kHeaderBytes, out.size() - kHeaderBytes));
  return out;
}


std::string Hex(std::uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

// Writes bytes atomically (temp file, fsync, rename); on failure *why says what went wrong.
bool WriteAtomically(const std::filesystem::path& target, const std::string& bytes, std::string* why) {
  AtomicFile file(target);
  Status s = file.Open();
  if (s) s = file.Write(bytes);
  if (s) s = file.Commit();
  if (!s) *why = s.error().message;
  return s.ok();
}

}  // namespace

std::uint64_t ScanContentHash(const Scan& scan) {
  Hasher h(0xC0FFEEULL);
  h.AddValue(static_cast<std::int64_t>(scan.rows));
  h.AddValue(static_cast<std::int64_t>(scan.cols));
  h.Add(scan.points.data(), scan.points.size() * sizeof(Eigen::Vector3f));
  h.Add(scan.reflectance.data(), scan.reflectance.size() * sizeof(float));
  h.Add(scan.valid.data(), scan.valid.size());
  if (!scan.list_points.empty()) {  // a scan without listed points keeps the key it had
    h.Add(scan.list_points.data(), scan.list_points.size() * sizeof(Eigen::Vector3f));
    h.Add(scan.list_reflectance.data(), scan.list_reflectance.size() * sizeof(float));
  }
  return h.Digest();
}

std::uint64_t FeatureCacheKey(const Scan& scan, const SiftOptions& options) {
  Hasher h(kDetectorVersion);
  h.AddValue(ScanContentHash(scan));
  h.AddValue(static_cast<std::int64_t>(options.max_features));
  h.AddValue(options.contrast_threshold);
  h.AddValue(options.edge_threshold);
  h.AddValue(options.sigma);
  h.AddValue(static_cast<std::int64_t>(options.octave_layers));
  h.AddValue(static_cast<std::int64_t>(options.mask_erosion_px));
  h.AddValue(static_cast<std::int64_t>(options.wrap_margin_px));
  // Strips (a large panorama): they change the keypoints near their borders.
  if (const int strips = SiftStrips(scan, options); strips > 1) {
    h.AddValue(static_cast<std::int64_t>(strips));
    h.AddValue(static_cast<std::int64_t>(kStripOverlapPx));
  }
  // A half-size detection image (a wide panorama) finds other keypoints.
  if (const int scale = SiftImageScale(scan, options); scale > 1) h.AddValue(static_cast<std::int64_t>(scale));
  // The angular grid decides whether the 360° wrap applies.
  h.Add(scan.angles.azimuth.data(), scan.angles.azimuth.size() * sizeof(float));
  const std::string opencv = CV_VERSION;  // another OpenCV may detect differently
  h.Add(opencv.data(), opencv.size());
  return h.Digest();
}

std::filesystem::path FeatureCachePath(const Scan& scan, const SiftOptions& options,
                                       const std::filesystem::path& cache_dir) {
  return cache_dir / ("sift_" + Hex(FeatureCacheKey(scan, options)) + ".feat");
}

Expected<ScanFeatures> ParseFeatureCacheEntry(const std::string& in, std::uint64_t key, const Scan& scan) {
  auto bad = [](const std::string& why) { return MakeError(ErrorCode::kParseError, why); };
  if (in.size() < kHeaderBytes + 8) return bad("truncated header (" + std::to_string(in.size()) + " bytes)");
  if (std::memcmp(in.data(), kMagic, 8) != 0) return bad("not a feature cache file (bad magic)");
  std::size_t pos = 8;
  if (Get<std::uint32_t>(in, pos) != kFormatVersion) return bad("unsupported format version");
  if (Get<std::uint32_t>(in, pos) != kSiftDescriptorSize) return bad("unexpected descriptor size");
  if (Get<std::uint64_t>(in, pos) != key) return bad("the entry belongs to another scan or options");
  ScanFeatures f;
  f.rows = Get<std::int32_t>(in, pos);
  f.cols = Get<std::int32_t>(in, pos);
  const auto n = Get<std::uint64_t>(in, pos);
  if (f.rows != scan.rows || f.cols != scan.cols) return bad("grid size differs from the scan's");
  const std::uint64_t per_feature = (kKeypointFloats + kSiftDescriptorSize) * sizeof(float);
  if (n > (in.size() / per_feature) || in.size() != kHeaderBytes + n * per_feature + 8)
    return bad("size " + std::to_string(in.size()) + " bytes does not match " + std::to_string(n) + " features");
  std::size_t checksum_pos = in.size() - 8;
  if (Get<std::uint64_t>(in, checksum_pos) != PayloadChecksum(in.data() + kHeaderBytes, in.size() - kHeaderBytes - 8))
    return bad("checksum mismatch (corrupt data)");
  f.keypoints.resize(n);
  for (auto& k : f.keypoints) {
    float values[kKeypointFloats];
    std::memcpy(values, in.data() + pos, sizeof(values));
    pos += sizeof(values);
    k = Keypoint{values[0], values[1], values[2], values[3], values[4]};
  }
  f.descriptors.resize(n * kSiftDescriptorSize);
  if (n > 0)  // memcpy from or to a null pointer is undefined even for 0 bytes (UBSan)
    std::memcpy(f.descriptors.data(), in.data() + pos, f.descriptors.size() * sizeof(float));
  return f;
}

Expected<ScanFeatures> LoadOrDetectFeatures(const Scan& scan, const SiftOptions& options,
                                            const std::filesystem::path& cache_dir, bool* from_cache) {
  if (from_cache) *from_cache = false;
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = scan.Validate(); !s) return s.error();
  const std::uint64_t key = FeatureCacheKey(scan, options);
  const std::filesystem::path path = cache_dir / ("sift_" + Hex(key) + ".feat");

  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.bad()) {
      Expected<ScanFeatures> cached = ParseFeatureCacheEntry(bytes, key, scan);
      if (cached) {
        if (from_cache) *from_cache = true;
        return cached;
      }
      LogWarning("feature cache: ignoring " + path.string() + " for scan '" + scan.name + "' (" +
                 cached.error().message + "); detecting the features again");
    } else {
      LogWarning("feature cache: cannot read " + path.string() + "; detecting the features of scan '" + scan.name +
                 "' again");
    }
  }

  Expected<ScanFeatures> features = DetectFeatures(scan, options);
  if (!features) return features;
  std::filesystem::create_directories(cache_dir, ec);
  if (ec) {
    LogWarning("feature cache: cannot create " + cache_dir.string() + " (" + ec.message() +
               "); the features of scan '" + scan.name + "' are not cached");
    return features;
  }
  std::string why;
  if (!WriteAtomically(path, Serialize(*features, key), &why))
    LogWarning("feature cache: " + why + "; the features of scan '" + scan.name + "' are not cached");
  return features;
}

}  // namespace scanreg
