#include "core/registration/voxel_filter.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <unordered_set>

namespace scanreg {
namespace {

struct VoxelKey {
  std::int64_t x, y, z;
  bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

// Voxel -> slot, open addressing with linear probing (power-of-two capacity, at most half full):
// a scan's 2 M points hashed into a node-based std::unordered_map cost ~0.15 s a scan, most of it
// allocating nodes (issue 36).
class VoxelSlots {
 public:
  static constexpr std::uint32_t kEmpty = 0xFFFFFFFFu;
  explicit VoxelSlots(std::size_t expected) { Rehash(std::max<std::size_t>(64, NextPow2(2 * expected))); }
  // The slot of `key`, or `next` stored as its slot when the key is new (*inserted true).
  std::uint32_t FindOrInsert(const VoxelKey& key, std::uint32_t next, bool* inserted) {
    if (2 * (size_ + 1) > keys_.size()) Rehash(2 * keys_.size());
    std::size_t i = Hash(key) & mask_;
    while (slots_[i] != kEmpty) {
      if (keys_[i] == key) {
        *inserted = false;
        return slots_[i];
      }
      i = (i + 1) & mask_;
    }
    keys_[i] = key;
    slots_[i] = next;
    ++size_;
    *inserted = true;
    return next;
  }

 private:
  static std::size_t NextPow2(std::size_t n) {
    std::size_t p = 1;
    while (p < n) p <<= 1;
    return p;
  }
  static std::size_t Hash(const VoxelKey& k) {
    std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ULL;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4FULL;
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ULL;
    return static_cast<std::size_t>(h ^ (h >> 29));
  }
  void Rehash(std::size_t capacity) {
    std::vector<VoxelKey> old_keys = std::move(keys_);
    std::vector<std::uint32_t> old_slots = std::move(slots_);
    keys_.assign(capacity, VoxelKey{0, 0, 0});
    slots_.assign(capacity, kEmpty);
    mask_ = capacity - 1;
    for (std::size_t j = 0; j < old_slots.size(); ++j) {
      if (old_slots[j] == kEmpty) continue;
      std::size_t i = Hash(old_keys[j]) & mask_;
      while (slots_[i] != kEmpty) i = (i + 1) & mask_;
      keys_[i] = old_keys[j];
      slots_[i] = old_slots[j];
    }
  }

  std::vector<VoxelKey> keys_;
  std::vector<std::uint32_t> slots_;
  std::size_t mask_ = 0, size_ = 0;
};

// A point's exact bits, for finding repeats.
struct PointBits {
  std::uint32_t x, y, z;
  bool operator==(const PointBits& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PointBitsHash {
  std::size_t operator()(const PointBits& b) const {
    return static_cast<std::size_t>((std::uint64_t(b.x) * 0x9E3779B97F4A7C15ULL) ^ (std::uint64_t(b.y) * 0xC2B2AE3D27D4EB4FULL) ^
                                    (std::uint64_t(b.z) * 0x165667B19E3779F9ULL));
  }
};
PointBits BitsOf(const Eigen::Vector3f& p) {
  PointBits b;
  std::memcpy(&b.x, &p.x(), 4), std::memcpy(&b.y, &p.y(), 4), std::memcpy(&b.z, &p.z(), 4);
  return b;
}

}  // namespace

std::vector<Eigen::Vector3d> ValidPoints(const Scan& scan) {
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(scan.CountPoints());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) pts.push_back(scan.points[i].cast<double>());
  // Seen from one place, the grid samples every surface and the list holds only a cell's losers
  // (repeats, neighbours within the angular step). A cloud seen from several places lists surfaces
  // the grid misses: its listed points that repeat no point before them are added (a file that
  // holds every point twice would otherwise weigh every neighbourhood double).
  if (scan.list_points.empty() || scan.single_viewpoint) return pts;
  std::unordered_set<PointBits, PointBitsHash> listed, seen;
  listed.reserve(scan.list_points.size());
  for (const Eigen::Vector3f& p : scan.list_points) listed.insert(BitsOf(p));
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i] && listed.count(BitsOf(scan.points[i]))) seen.insert(BitsOf(scan.points[i]));
  for (const Eigen::Vector3f& p : scan.list_points)
    if (seen.insert(BitsOf(p)).second) pts.push_back(p.cast<double>());
  return pts;
}

std::vector<Eigen::Vector3d> VoxelDownsample(const std::vector<Eigen::Vector3d>& points, double voxel_m) {
  std::vector<Eigen::Vector3d> out;
  if (!(voxel_m > 0.0)) {
    for (const auto& p : points)
      if (p.allFinite()) out.push_back(p);
    return out;
  }
  VoxelSlots slot(points.size() / 8 + 16);
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  const double inv = 1.0 / voxel_m;
  // A scan's consecutive points mostly share a voxel: the last one's slot is tried before the hash.
  VoxelKey last_key{0, 0, 0};
  std::uint32_t last_slot = VoxelSlots::kEmpty;
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const VoxelKey key{static_cast<std::int64_t>(std::floor(p.x() * inv)), static_cast<std::int64_t>(std::floor(p.y() * inv)),
                       static_cast<std::int64_t>(std::floor(p.z() * inv))};
    if (last_slot != VoxelSlots::kEmpty && key == last_key) {
      sum[last_slot] += p;
      ++count[last_slot];
      continue;
    }
    bool inserted = false;
    const std::uint32_t s = slot.FindOrInsert(key, static_cast<std::uint32_t>(sum.size()), &inserted);
    if (inserted) {
      sum.push_back(p);
      count.push_back(1);
    } else {
      sum[s] += p;
      ++count[s];
    }
    last_key = key;
    last_slot = s;
  }
  out.resize(sum.size());
  for (std::size_t i = 0; i < sum.size(); ++i) out[i] = sum[i] / count[i];
  return out;
}

std::vector<Eigen::Vector3d> ThinEvenly(std::vector<Eigen::Vector3d> points, int max_count) {
  if (max_count <= 0 || static_cast<int>(points.size()) <= max_count) return points;
  std::vector<Eigen::Vector3d> out;
  out.reserve(max_count);
  const double stride = double(points.size()) / max_count;
  for (int i = 0; i < max_count; ++i) out.push_back(points[static_cast<std::size_t>(i * stride)]);
  return out;
}

std::vector<Eigen::Vector3d> ThinEvenly(const std::vector<Eigen::Vector3f>& points, int max_count) {
  if (max_count <= 0 || static_cast<int>(points.size()) <= max_count) return ToDouble(points);
  std::vector<Eigen::Vector3d> out;
  out.reserve(max_count);
  const double stride = double(points.size()) / max_count;
  for (int i = 0; i < max_count; ++i) out.push_back(points[static_cast<std::size_t>(i * stride)].cast<double>());
  return out;
}

std::vector<Eigen::Vector3f> ToFloat(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(points.size());
  for (const Eigen::Vector3d& p : points) out.push_back(p.cast<float>());
  return out;
}

std::vector<Eigen::Vector3d> ToDouble(const std::vector<Eigen::Vector3f>& points) {
  std::vector<Eigen::Vector3d> out;
  out.reserve(points.size());
  for (const Eigen::Vector3f& p : points) out.push_back(p.cast<double>());
  return out;
}

}  // namespace scanreg
