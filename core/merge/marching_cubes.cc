#include "core/merge/marching_cubes.h"

#include "core/merge/distance_field.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace scanreg::merge {

namespace {

#include "core/merge/marching_cubes_tables.inc"

// Corner offsets in PCL's numbering of Bourke's cube, and the corners of each edge.
constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}};
constexpr int kEdgeCorners[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                     {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};

}  // namespace

Mesh ExtractMesh(const SparseGrid& grid) {
  MeshBuilder builder;
  builder.Add(grid);
  return std::move(builder.mesh());
}

namespace {

// One block's cubes: vertices on the edges only its own cubes touch (local ids), the edges it shares
// with neighbouring blocks (resolved through the builder's map), and triangles referring to either
// (r >= 0: local vertex r; r < 0: shared edge -r - 1).
struct BlockPiece {
  std::vector<Eigen::Vector3f> vertices;
  // Per local vertex: every cube around its edge has a filled corner (without the filled values no
  // cube would have made it).
  std::vector<std::uint8_t> on_filled;
  struct Shared {
    std::array<int, 4> key;  // (i, j, k, axis)
    Eigen::Vector3f position;
    std::uint8_t on_filled;
  };
  std::vector<Shared> shared;
  std::vector<Eigen::Vector3i> triangles;
};

void MeshBlock(const SparseGrid& grid, const SparseGrid::Block& b, BlockPiece* piece) {
  constexpr int B = SparseGrid::kBlock, P = B + 1;
  SparseGrid::Neighbourhood around, weight;
  grid.Gather(b, &around, &weight);
  const float h = float(grid.voxel());
  // Interior edges' local vertex ids, by lower end (0..B on each axis) and axis.
  std::array<int, P * P * P * 3> local;
  local.fill(-1);
  for (int z = 0; z < B; ++z) {
    for (int y = 0; y < B; ++y) {
      for (int x = 0; x < B; ++x) {
        float v[8];
        bool filled[8];
        bool known = true;
        for (int c = 0; c < 8 && known; ++c) {
          const int at = SparseGrid::Padded(x + kCorner[c][0], y + kCorner[c][1], z + kCorner[c][2]);
          v[c] = around[at];
          filled[c] = weight[at] <= kFilledWeight;
          known = !std::isnan(v[c]);
        }
        if (!known) continue;
        const std::uint8_t cube_filled = std::any_of(filled, filled + 8, [](bool f) { return f; });
        int cube = 0;
        for (int c = 0; c < 8; ++c) cube |= (v[c] < 0.0f) << c;
        if (kEdgeTable[cube] == 0) continue;
        int ids[12];
        for (int e = 0; e < 12; ++e) {
          if (!(kEdgeTable[cube] & (1u << e))) continue;
          int c0 = kEdgeCorners[e][0], c1 = kEdgeCorners[e][1];
          // Key by the edge's lower end so that neighbouring cubes find the same vertex.
          int axis = 0;
          for (int a = 0; a < 3; ++a) {
            if (kCorner[c0][a] != kCorner[c1][a]) axis = a;
          }
          if (kCorner[c0][axis] > kCorner[c1][axis]) std::swap(c0, c1);
          const int end[3] = {x + kCorner[c0][0], y + kCorner[c0][1], z + kCorner[c0][2]};
          // The four cubes around the edge are all this block's when its other coordinates are 1..B-1.
          bool interior = true;
          for (int a = 0; a < 3; ++a) interior = interior && (a == axis || (end[a] >= 1 && end[a] < B));
          const std::array<int, 4> key{b.key.x * B + end[0], b.key.y * B + end[1], b.key.z * B + end[2], axis};
          auto position = [&] {
            const float t = v[c0] / (v[c0] - v[c1]);
            Eigen::Vector3f p = Eigen::Vector3f(float(key[0]), float(key[1]), float(key[2]));
            p[axis] += t;
            return Eigen::Vector3f(p * h);
          };
          if (interior) {
            int& id = local[((end[2] * P + end[1]) * P + end[0]) * 3 + axis];
            if (id < 0) {
              id = int(piece->vertices.size());
              piece->vertices.push_back(position());
              piece->on_filled.push_back(cube_filled);
            } else {
              piece->on_filled[id] &= cube_filled;
            }
            ids[e] = id;
          } else {
            ids[e] = -int(piece->shared.size()) - 1;  // the same edge twice in a block: the map joins them
            piece->shared.push_back({key, position(), cube_filled});
          }
        }
        for (int t = 0; kTriTable[cube][t] != -1; t += 3) {
          // Wound counter-clockwise seen from outside (positive side) for this corner numbering.
          piece->triangles.emplace_back(ids[kTriTable[cube][t]], ids[kTriTable[cube][t + 1]], ids[kTriTable[cube][t + 2]]);
        }
      }
    }
  }
}

}  // namespace

void MeshBuilder::Add(const SparseGrid& grid, const SparseGrid::Bounds* own) {
  mesh_.origin = grid.origin();
  std::vector<std::size_t> blocks;
  for (std::size_t bi = 0; bi < grid.num_blocks(); ++bi) {
    if (!own || own->Contains(grid.block(bi).key)) blocks.push_back(bi);
  }
  // Blocks meshed in parallel a batch at a time, joined in block order (the same mesh whatever the
  // thread count).
  constexpr std::size_t kBatch = 1024;
  std::vector<BlockPiece> pieces(kBatch);
  std::vector<int> shared_id;
  for (std::size_t first = 0; first < blocks.size(); first += kBatch) {
    const long count = long(std::min(kBatch, blocks.size() - first));
#pragma omp parallel for schedule(dynamic, 8)
    for (long i = 0; i < count; ++i) {
      pieces[i] = BlockPiece();
      MeshBlock(grid, grid.block(blocks[first + i]), &pieces[i]);
    }
    for (long i = 0; i < count; ++i) {
      const BlockPiece& piece = pieces[i];
      const int offset = flushed_ + int(mesh_.vertices.size());
      mesh_.vertices.insert(mesh_.vertices.end(), piece.vertices.begin(), piece.vertices.end());
      mesh_.on_filled.insert(mesh_.on_filled.end(), piece.on_filled.begin(), piece.on_filled.end());
      shared_id.clear();
      for (const BlockPiece::Shared& s : piece.shared) {
        const auto [it, fresh] = vertex_of_.try_emplace(EdgeKey{s.key[0], s.key[1], s.key[2], s.key[3]},
                                                        flushed_ + int(mesh_.vertices.size()));
        if (fresh) {
          mesh_.vertices.push_back(s.position);
          mesh_.on_filled.push_back(s.on_filled);
        } else if (it->second >= flushed_) {  // a vertex taken already keeps its mark (a tile border)
          mesh_.on_filled[std::size_t(it->second - flushed_)] &= s.on_filled;
        }
        shared_id.push_back(it->second);
      }
      for (const Eigen::Vector3i& t : piece.triangles) {
        Eigen::Vector3i g;
        for (int c = 0; c < 3; ++c) g[c] = t[c] >= 0 ? offset + t[c] : shared_id[-t[c] - 1];
        mesh_.triangles.push_back(g);
      }
    }
  }
}

Mesh MeshBuilder::Take() {
  Mesh taken = std::move(mesh_);
  mesh_ = Mesh();
  mesh_.origin = taken.origin;
  mesh_.coloured = taken.coloured;
  flushed_ += int(taken.vertices.size());
  return taken;
}

void MeshBuilder::Forget(const std::function<bool(int i, int j)>& done) {
  for (auto it = vertex_of_.begin(); it != vertex_of_.end();) {
    const EdgeKey& e = it->first;  // the cubes around it have lowest points (i - 1 .. i, j - 1 .. j)
    if (done(e.i - 1, e.j - 1) && done(e.i, e.j - 1) && done(e.i - 1, e.j) && done(e.i, e.j)) {
      it = vertex_of_.erase(it);
    } else {
      ++it;
    }
  }
}

}  // namespace scanreg::merge
