#include "core/registration/voxel_filter.h"

#include <cmath>
#include <limits>
#include <cstdint>
#include <cstring>
#include <unordered_map>
#include <unordered_set>

namespace scanreg {
namespace {

struct VoxelKey {
  std::int64_t x, y, z;
  bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

struct VoxelKeyHash {
  std::size_t operator()(const VoxelKey& k) const {
    // Teschner et al. 2003 spatial hash.
    return static_cast<std::size_t>((static_cast<std::uint64_t>(k.x) * 73856093u) ^
                                    (static_cast<std::uint64_t>(k.y) * 19349663u) ^
                                    (static_cast<std::uint64_t>(k.z) * 83492791u));
  }
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
  std::unordered_map<VoxelKey, std::size_t, VoxelKeyHash> slot;
  slot.reserve(points.size() / 4 + 16);
  std::vector<Eigen::Vector3d> sum;
  std::vector<int> count;
  const double inv = 1.0 / voxel_m;
  // A scan's consecutive points mostly share a voxel: the last one's slot is tried before the hash.
  VoxelKey last_key{0, 0, 0};
  std::size_t last_slot = std::numeric_limits<std::size_t>::max();
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    const VoxelKey key{static_cast<std::int64_t>(std::floor(p.x() * inv)), static_cast<std::int64_t>(std::floor(p.y() * inv)),
                       static_cast<std::int64_t>(std::floor(p.z() * inv))};
    if (last_slot != std::numeric_limits<std::size_t>::max() && key == last_key) {
      sum[last_slot] += p;
      ++count[last_slot];
      continue;
    }
    auto [it, inserted] = slot.try_emplace(key, sum.size());
    if (inserted) {
      sum.push_back(p);
      count.push_back(1);
    } else {
      sum[it->second] += p;
      ++count[it->second];
    }
    last_key = key;
    last_slot = it->second;
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
