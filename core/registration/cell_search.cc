#include "core/registration/cell_search.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scanreg {
namespace {

// FLANN's L2_Simple: the squared differences summed in float, x then y then z.
float SquaredDistance(const pcl::PointXYZ& q, const pcl::PointXYZ& p) {
  float d = 0.0f, t = q.x - p.x;
  d += t * t;
  t = q.y - p.y;
  d += t * t;
  t = q.z - p.z;
  d += t * t;
  return d;
}

}  // namespace

CellSearch::CellSearch(double cell_m)
    : pcl::search::Search<pcl::PointXYZ>("CellSearch", true), cell_m_(cell_m) {}

CellSearch::Key CellSearch::KeyOf(float x, float y, float z) const {
  const auto c = [&](float v) {
    const double k = std::floor(double(v) / cell_m_);
    return static_cast<std::int32_t>(std::clamp(k, -1e9, 1e9));
  };
  return {c(x), c(y), c(z)};
}

std::size_t CellSearch::Slot(const Key& k) const {
  std::uint64_t h = static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.x)) * 0x9E3779B97F4A7C15ULL;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.y)) * 0xC2B2AE3D27D4EB4FULL;
  h ^= static_cast<std::uint64_t>(static_cast<std::uint32_t>(k.z)) * 0x165667B19E3779F9ULL;
  return static_cast<std::size_t>(h ^ (h >> 29)) & mask_;
}

std::pair<std::uint32_t, std::uint32_t> CellSearch::Cell(const Key& key) const {
  if (slot_key_.empty()) return {0, 0};
  for (std::size_t i = Slot(key);; i = (i + 1) & mask_) {
    if (slot_begin_[i] == slot_end_[i]) return {0, 0};  // empty slot: no such cell
    if (slot_key_[i] == key) return {slot_begin_[i], slot_end_[i]};
  }
}

void CellSearch::setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) {
  input_ = cloud;
  indices_ = indices;
  order_.clear();
  slot_key_.clear();
  slot_begin_.clear();
  slot_end_.clear();
  if (!cloud) return;
  std::vector<std::pair<Key, int>> keyed;  // each finite point's cell, then its index
  const auto add = [&](int i) {
    const pcl::PointXYZ& p = (*cloud)[i];
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) keyed.emplace_back(KeyOf(p.x, p.y, p.z), i);
  };
  if (indices) {
    for (int i : *indices) add(i);
  } else {
    for (int i = 0; i < static_cast<int>(cloud->size()); ++i) add(i);
  }
  std::sort(keyed.begin(), keyed.end());
  // At most half full whatever the number of cells (at most one a point).
  std::size_t capacity = 64;
  while (capacity < 2 * keyed.size()) capacity <<= 1;
  mask_ = capacity - 1;
  slot_key_.assign(capacity, Key{});
  slot_begin_.assign(capacity, 0);
  slot_end_.assign(capacity, 0);
  for (const auto& [key, i] : keyed) order_.push_back(i);
  for (std::size_t begin = 0; begin < keyed.size();) {
    const Key key = keyed[begin].first;
    std::size_t end = begin + 1;
    while (end < keyed.size() && keyed[end].first == key) ++end;
    std::size_t slot = Slot(key);
    while (slot_begin_[slot] != slot_end_[slot]) slot = (slot + 1) & mask_;
    slot_key_[slot] = key;
    slot_begin_[slot] = static_cast<std::uint32_t>(begin);
    slot_end_[slot] = static_cast<std::uint32_t>(end);
    begin = end;
  }
}

void CellSearch::Collect(const pcl::PointXYZ& q, float radius2, int reach, std::vector<std::pair<float, int>>* out) const {
  out->clear();
  if (!input_ || order_.empty()) return;
  const Key c = KeyOf(q.x, q.y, q.z);
  const pcl::PointCloud<pcl::PointXYZ>& cloud = *input_;
  for (int dx = -reach; dx <= reach; ++dx)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dz = -reach; dz <= reach; ++dz) {
        const auto [begin, end] = Cell({c.x + dx, c.y + dy, c.z + dz});
        for (std::uint32_t k = begin; k < end; ++k) {
          const float d = SquaredDistance(q, cloud[order_[k]]);
          if (d < radius2) out->emplace_back(d, order_[k]);
        }
      }
}

int CellSearch::radiusSearch(const pcl::PointXYZ& point, double radius, pcl::Indices& k_indices,
                             std::vector<float>& k_sqr_distances, unsigned int max_nn) const {
  k_indices.clear();
  k_sqr_distances.clear();
  if (!(radius > 0) || !std::isfinite(point.x) || !std::isfinite(point.y) || !std::isfinite(point.z)) return 0;
  const int reach = static_cast<int>(std::ceil(radius / cell_m_));
  thread_local std::vector<std::pair<float, int>> found;
  Collect(point, static_cast<float>(radius * radius), reach, &found);
  std::sort(found.begin(), found.end());  // by distance, then index: FLANN's sorted order
  if (max_nn > 0 && found.size() > max_nn) found.resize(max_nn);
  for (const auto& [d, i] : found) {
    k_indices.push_back(i);
    k_sqr_distances.push_back(d);
  }
  return static_cast<int>(found.size());
}

int CellSearch::nearestKSearch(const pcl::PointXYZ& point, int k, pcl::Indices& k_indices,
                               std::vector<float>& k_sqr_distances) const {
  k_indices.clear();
  k_sqr_distances.clear();
  if (k <= 0 || order_.empty() || !std::isfinite(point.x) || !std::isfinite(point.y) || !std::isfinite(point.z)) return 0;
  const int want = std::min<int>(k, static_cast<int>(order_.size()));
  thread_local std::vector<std::pair<float, int>> found;
  // Grow the cube of cells until it holds k points all nearer than the cube's inner radius.
  for (int reach = 1;; reach *= 2) {
    // Beyond as many cells as points, every point at once.
    const double cube = std::pow(2.0 * reach + 1.0, 3);
    const bool everything = cube > static_cast<double>(order_.size());
    if (everything) {
      found.clear();
      for (int i : order_) found.emplace_back(SquaredDistance(point, (*input_)[i]), i);
    } else {
      Collect(point, std::numeric_limits<float>::infinity(), reach, &found);
    }
    if (static_cast<int>(found.size()) < want && !everything) continue;
    std::partial_sort(found.begin(), found.begin() + want, found.end());
    const double inner = reach * cell_m_;
    if (everything || found[want - 1].first <= inner * inner) break;
  }
  for (int i = 0; i < want; ++i) {
    k_indices.push_back(found[i].second);
    k_sqr_distances.push_back(found[i].first);
  }
  return want;
}

}  // namespace scanreg
