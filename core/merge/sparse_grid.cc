#include "core/merge/sparse_grid.h"

#include <cmath>

namespace scanreg::merge {
namespace {

// The blocks holding a grid point within band_m of p: lo..hi on each axis.
void BlockRange(const Eigen::Vector3f& p, double voxel_m, double band_m, int lo[3], int hi[3]) {
  const double inv = 1.0 / voxel_m;
  for (int a = 0; a < 3; ++a) {
    lo[a] = FloorDiv(int(std::ceil((p[a] - band_m) * inv)), SparseGrid::kBlock);
    hi[a] = FloorDiv(int(std::floor((p[a] + band_m) * inv)), SparseGrid::kBlock);
  }
}

}  // namespace

void SparseGrid::AllocateAround(const Eigen::Vector3f& p, double band_m) {
  int lo[3], hi[3];
  BlockRange(p, voxel_, band_m, lo, hi);
  for (int z = lo[2]; z <= hi[2]; ++z) {
    for (int y = lo[1]; y <= hi[1]; ++y) {
      for (int x = lo[0]; x <= hi[0]; ++x) {
        const BlockKey key{x, y, z};
        if ((bounded_ && !bounds_.Contains(key)) || index_.count(key)) continue;
        index_.emplace(key, blocks_.size());
        Block& b = blocks_.emplace_back();
        b.key = key;
        b.distance.fill(0.0f);
        b.weight.fill(0.0f);
      }
    }
  }
}

bool BlockCounter::Add(const Eigen::Vector3f& p) {
  if (capped()) return false;
  int lo[3], hi[3];
  BlockRange(p, voxel_, band_, lo, hi);
  // Neighbouring points mostly touch the blocks of the one before: six comparisons, no look-up.
  const BlockKey first{lo[0], lo[1], lo[2]}, last{hi[0], hi[1], hi[2]};
  if (has_last_ && first == last_lo_ && last == last_hi_) return true;
  last_lo_ = first, last_hi_ = last, has_last_ = true;
  for (int z = lo[2]; z <= hi[2]; ++z)
    for (int y = lo[1]; y <= hi[1]; ++y)
      for (int x = lo[0]; x <= hi[0]; ++x) {
        keys_.insert(BlockKey{x, y, z});
        if (capped()) return false;
      }
  return true;
}

std::size_t SparseGrid::MemoryBytes() const {
  return blocks_.capacity() * sizeof(Block) + index_.size() * (sizeof(BlockKey) + sizeof(std::size_t) + 16);
}

const SparseGrid::Block* SparseGrid::Find(const BlockKey& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? nullptr : &blocks_[it->second];
}

bool SparseGrid::Sample(int i, int j, int k, float* distance) const {
  const BlockKey key{FloorDiv(i, kBlock), FloorDiv(j, kBlock), FloorDiv(k, kBlock)};
  const Block* b = Find(key);
  if (!b) return false;
  const int l = Local(i - key.x * kBlock, j - key.y * kBlock, k - key.z * kBlock);
  if (b->weight[l] <= 0.0f) return false;
  *distance = b->distance[l];
  return true;
}

std::size_t FixIsolatedSigns(SparseGrid& grid) {
  constexpr int B = SparseGrid::kBlock;
  const float min_abs = float(grid.voxel());
  std::vector<std::vector<int>> flips(grid.num_blocks());
#pragma omp parallel for schedule(dynamic, 16)
  for (long bi = 0; bi < long(grid.num_blocks()); ++bi) {
    const SparseGrid::Block& b = grid.block(bi);
    for (int z = 0; z < B; ++z) {
      for (int y = 0; y < B; ++y) {
        for (int x = 0; x < B; ++x) {
          const int l = SparseGrid::Local(x, y, z);
          if (b.weight[l] <= 0.0f || std::abs(b.distance[l]) < min_abs) continue;
          const bool positive = b.distance[l] > 0.0f;
          const int i = b.key.x * B + x, j = b.key.y * B + y, k = b.key.z * B + z;
          int known = 0, other = 0;
          for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
              for (int dx = -1; dx <= 1; ++dx) {
                float d;
                if ((dx || dy || dz) && grid.Sample(i + dx, j + dy, k + dz, &d)) ++known, other += (d > 0.0f) != positive;
              }
            }
          }
          if (known >= 6 && 3 * other >= 2 * known) flips[bi].push_back(l);
        }
      }
    }
  }
  std::size_t n = 0;
  for (std::size_t bi = 0; bi < flips.size(); ++bi) {
    for (int l : flips[bi]) grid.block(bi).distance[l] = -grid.block(bi).distance[l], ++n;
  }
  return n;
}

void SmoothField(SparseGrid& grid, int iterations) {
  constexpr int B = SparseGrid::kBlock;
  for (int it = 0; it < iterations; ++it) {
    std::vector<std::array<float, SparseGrid::kVoxels>> out(grid.num_blocks());
#pragma omp parallel for schedule(dynamic, 16)
    for (long bi = 0; bi < long(grid.num_blocks()); ++bi) {
      const SparseGrid::Block& b = grid.block(bi);
      out[bi] = b.distance;
      for (int z = 0; z < B; ++z) {
        for (int y = 0; y < B; ++y) {
          for (int x = 0; x < B; ++x) {
            if (b.weight[SparseGrid::Local(x, y, z)] <= 0.0f) continue;
            const int i = b.key.x * B + x, j = b.key.y * B + y, k = b.key.z * B + z;
            double sum = 0.0;
            int n = 0;
            for (int dz = -1; dz <= 1; ++dz) {
              for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                  float d;
                  if (grid.Sample(i + dx, j + dy, k + dz, &d)) sum += d, ++n;
                }
              }
            }
            out[bi][SparseGrid::Local(x, y, z)] = float(sum / n);
          }
        }
      }
    }
    for (std::size_t bi = 0; bi < grid.num_blocks(); ++bi) grid.block(bi).distance = out[bi];
  }
}

}  // namespace scanreg::merge
