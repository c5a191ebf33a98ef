#include "core/merge/sparse_grid.h"

#include <cmath>
#include <limits>

namespace scanreg::merge {

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

void SparseGrid::Gather(const Block& b, Neighbourhood* out, Neighbourhood* weights) const {
  constexpr int B = kBlock;
  const Block* around[27];
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        around[(dz + 1) * 9 + (dy + 1) * 3 + dx + 1] =
            dx || dy || dz ? Find(BlockKey{b.key.x + dx, b.key.y + dy, b.key.z + dz}) : &b;
  // Which neighbour and local coordinate each padded coordinate -1..B falls in.
  auto side = [](int v) { return v < 0 ? 0 : (v < B ? 1 : 2); };
  auto wrap = [](int v) { return v < 0 ? v + B : (v < B ? v : v - B); };
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int z = -1; z <= B; ++z) {
    for (int y = -1; y <= B; ++y) {
      for (int x = -1; x <= B; ++x) {
        const Block* n = around[side(z) * 9 + side(y) * 3 + side(x)];
        float v = nan, w = 0.0f;
        if (n) {
          const int l = Local(wrap(x), wrap(y), wrap(z));
          if (n->weight[l] > 0.0f) v = n->distance[l], w = n->weight[l];
        }
        (*out)[Padded(x, y, z)] = v;
        if (weights) (*weights)[Padded(x, y, z)] = w;
      }
    }
  }
}

std::size_t FixIsolatedSigns(SparseGrid& grid) {
  constexpr int B = SparseGrid::kBlock;
  const float min_abs = float(grid.voxel());
  std::vector<std::vector<int>> flips(grid.num_blocks());
#pragma omp parallel for schedule(dynamic, 16)
  for (long bi = 0; bi < long(grid.num_blocks()); ++bi) {
    const SparseGrid::Block& b = grid.block(bi);
    SparseGrid::Neighbourhood around;
    grid.Gather(b, &around);
    for (int z = 0; z < B; ++z) {
      for (int y = 0; y < B; ++y) {
        for (int x = 0; x < B; ++x) {
          const int l = SparseGrid::Local(x, y, z);
          if (b.weight[l] <= 0.0f || std::abs(b.distance[l]) < min_abs) continue;
          const bool positive = b.distance[l] > 0.0f;
          int known = 0, other = 0;
          for (int dz = -1; dz <= 1; ++dz) {
            for (int dy = -1; dy <= 1; ++dy) {
              for (int dx = -1; dx <= 1; ++dx) {
                const float d = around[SparseGrid::Padded(x + dx, y + dy, z + dz)];
                if ((dx || dy || dz) && !std::isnan(d)) ++known, other += (d > 0.0f) != positive;
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
      SparseGrid::Neighbourhood around;
      grid.Gather(b, &around);
      out[bi] = b.distance;
      for (int z = 0; z < B; ++z) {
        for (int y = 0; y < B; ++y) {
          for (int x = 0; x < B; ++x) {
            if (b.weight[SparseGrid::Local(x, y, z)] <= 0.0f) continue;
            double sum = 0.0;
            int n = 0;
            for (int dz = -1; dz <= 1; ++dz) {
              for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                  const float d = around[SparseGrid::Padded(x + dx, y + dy, z + dz)];
                  if (!std::isnan(d)) sum += d, ++n;
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
