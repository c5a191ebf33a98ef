// A signed distance field on a sparse grid of hashed voxel blocks (8^3 voxels each): memory grows
// with the surface, not with the bounding box. Grid point (i, j, k) sits at origin + voxel * (i, j, k).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace scanreg::merge {

struct BlockKey {
  int x = 0, y = 0, z = 0;
  bool operator==(const BlockKey& o) const { return x == o.x && y == o.y && z == o.z; }
};

struct BlockKeyHash {
  std::size_t operator()(const BlockKey& k) const {
    return (std::size_t(std::uint32_t(k.x)) * 73856093u) ^ (std::size_t(std::uint32_t(k.y)) * 19349663u) ^
           (std::size_t(std::uint32_t(k.z)) * 83492791u);
  }
};

class SparseGrid {
 public:
  static constexpr int kBlock = 8;  // voxels per block edge
  static constexpr int kVoxels = kBlock * kBlock * kBlock;
  struct Block {
    BlockKey key;
    std::array<float, kVoxels> distance;  // metres, positive outside; meaningful where weight > 0
    std::array<float, kVoxels> weight;    // 0 = unknown
  };

  SparseGrid(const Eigen::Vector3d& origin, double voxel_m) : origin_(origin), voxel_(voxel_m) {}

  const Eigen::Vector3d& origin() const { return origin_; }
  double voxel() const { return voxel_; }

  // Allocates (unknown) every block holding a grid point within band_m of p (p relative to origin),
  // within the bounds when set, and calls visit(block index) for each of them, new or not.
  template <class Visit>
  void AllocateAround(const Eigen::Vector3f& p, double band_m, Visit&& visit);
  void AllocateAround(const Eigen::Vector3f& p, double band_m) {
    AllocateAround(p, band_m, [](std::size_t) {});
  }
  // Blocks lo..hi (inclusive, each axis) only: a tile of a tiled merge (merge.h).
  struct Bounds {
    BlockKey lo, hi;
    bool Contains(const BlockKey& k) const {
      return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
    }
  };
  void Restrict(const Bounds& bounds) { bounds_ = bounds, bounded_ = true; }
  std::size_t num_blocks() const { return blocks_.size(); }
  // Room for this many blocks before AllocateAround adds them (no reallocation peak on the way).
  void Reserve(std::size_t blocks) { blocks_.reserve(blocks), index_.reserve(blocks); }
  Block& block(std::size_t i) { return blocks_[i]; }
  const Block& block(std::size_t i) const { return blocks_[i]; }
  std::size_t MemoryBytes() const;

  // Grid point position relative to the origin.
  Eigen::Vector3f Position(const BlockKey& key, int vx, int vy, int vz) const {
    return Eigen::Vector3f(float(voxel_ * (key.x * kBlock + vx)), float(voxel_ * (key.y * kBlock + vy)),
                           float(voxel_ * (key.z * kBlock + vz)));
  }
  static int Local(int vx, int vy, int vz) { return (vz * kBlock + vy) * kBlock + vx; }
  // The distances around block b, at local coordinates -1..kBlock on each axis (x fastest; index
  // with Padded), NaN where unknown: one look-up per neighbouring block instead of one per voxel.
  static constexpr int kPadded = kBlock + 2;
  using Neighbourhood = std::array<float, kPadded * kPadded * kPadded>;
  static int Padded(int vx, int vy, int vz) { return ((vz + 1) * kPadded + vy + 1) * kPadded + vx + 1; }
  // `weights` (optional): the weights of the same grid points (0 where unknown).
  void Gather(const Block& b, Neighbourhood* out, Neighbourhood* weights = nullptr) const;
  const Block* Find(const BlockKey& key) const;

 private:
  Eigen::Vector3d origin_;
  double voxel_;
  std::vector<Block> blocks_;
  std::unordered_map<BlockKey, std::size_t, BlockKeyHash> index_;
  Bounds bounds_;
  bool bounded_ = false;
};

inline int FloorDiv(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// The blocks holding a grid point within band_m of p on every axis: lo..hi.
inline void BlockRange(const Eigen::Vector3f& p, double voxel_m, double band_m, int lo[3], int hi[3]) {
  const double inv = 1.0 / voxel_m;
  for (int a = 0; a < 3; ++a) {
    lo[a] = FloorDiv(int(std::ceil((p[a] - band_m) * inv)), SparseGrid::kBlock);
    hi[a] = FloorDiv(int(std::floor((p[a] + band_m) * inv)), SparseGrid::kBlock);
  }
}

template <class Visit>
void SparseGrid::AllocateAround(const Eigen::Vector3f& p, double band_m, Visit&& visit) {
  int lo[3], hi[3];
  BlockRange(p, voxel_, band_m, lo, hi);
  for (int z = lo[2]; z <= hi[2]; ++z) {
    for (int y = lo[1]; y <= hi[1]; ++y) {
      for (int x = lo[0]; x <= hi[0]; ++x) {
        const BlockKey key{x, y, z};
        if (bounded_ && !bounds_.Contains(key)) continue;
        const auto [it, added] = index_.try_emplace(key, blocks_.size());
        if (added) {
          Block& b = blocks_.emplace_back();
          b.key = key;
          b.distance.fill(0.0f);
          b.weight.fill(0.0f);
        }
        visit(it->second);
      }
    }
  }
}

// Counts the blocks SparseGrid::AllocateAround would allocate for a set of points, with a key set
// instead of the blocks (~1/60 of their memory), stopping at `cap`: what a merge will need, known
// before it allocates anything.
class BlockCounter {
 public:
  BlockCounter(double voxel_m, double band_m, std::size_t cap) : voxel_(voxel_m), band_(band_m), cap_(cap) {}
  // p relative to the grid's origin; false once the count has reached the cap.
  bool Add(const Eigen::Vector3f& p);
  std::size_t count() const { return keys_.size(); }
  bool capped() const { return keys_.size() >= cap_; }
  const std::unordered_set<BlockKey, BlockKeyHash>& keys() const { return keys_; }

 private:
  double voxel_, band_;
  std::size_t cap_;
  BlockKey last_lo_, last_hi_;  // the blocks of the previous point
  bool has_last_ = false;
  std::unordered_set<BlockKey, BlockKeyHash> keys_;
};

// Flips the sign of grid points at least one voxel from the zero level whose known 26 neighbours
// mostly (>= 2/3) have the other sign: isolated sign errors far from the surface would otherwise
// become bubbles or holes at the band's edge. Returns the number flipped.
std::size_t FixIsolatedSigns(SparseGrid& grid);

// Mean filter over the known 3x3x3 neighbours of each known grid point, `iterations` times.
void SmoothField(SparseGrid& grid, int iterations);

}  // namespace scanreg::merge
