#include "core/merge/marching_cubes.h"

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

void MeshBuilder::Add(const SparseGrid& grid, const SparseGrid::Bounds* own) {
  constexpr int B = SparseGrid::kBlock;
  Mesh& mesh = mesh_;
  auto& vertex_of = vertex_of_;
  mesh.origin = grid.origin();
  const float h = float(grid.voxel());
  for (std::size_t bi = 0; bi < grid.num_blocks(); ++bi) {
    const SparseGrid::Block& b = grid.block(bi);
    if (own && !own->Contains(b.key)) continue;
    for (int z = 0; z < B; ++z) {
      for (int y = 0; y < B; ++y) {
        for (int x = 0; x < B; ++x) {
          if (b.weight[SparseGrid::Local(x, y, z)] <= 0.0f) continue;
          const int gi = b.key.x * B + x, gj = b.key.y * B + y, gk = b.key.z * B + z;
          float v[8];
          bool known = true;
          const bool inside = x + 1 < B && y + 1 < B && z + 1 < B;
          for (int c = 0; c < 8 && known; ++c) {
            const int dx = kCorner[c][0], dy = kCorner[c][1], dz = kCorner[c][2];
            if (inside) {
              const int l = SparseGrid::Local(x + dx, y + dy, z + dz);
              known = b.weight[l] > 0.0f;
              v[c] = b.distance[l];
            } else {
              known = grid.Sample(gi + dx, gj + dy, gk + dz, &v[c]);
            }
          }
          if (!known) continue;
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
            const EdgeKey key{gi + kCorner[c0][0], gj + kCorner[c0][1], gk + kCorner[c0][2], axis};
            auto [it, fresh] = vertex_of.try_emplace(key, int(mesh.vertices.size()));
            if (fresh) {
              const float t = v[c0] / (v[c0] - v[c1]);
              Eigen::Vector3f p(float(key.i), float(key.j), float(key.k));
              p[axis] += t;
              mesh.vertices.push_back(p * h);
            }
            ids[e] = it->second;
          }
          for (int t = 0; kTriTable[cube][t] != -1; t += 3) {
            // Wound counter-clockwise seen from outside (positive side) for this corner numbering.
            mesh.triangles.emplace_back(ids[kTriTable[cube][t]], ids[kTriTable[cube][t + 1]],
                                        ids[kTriTable[cube][t + 2]]);
          }
        }
      }
    }
  }
}

}  // namespace scanreg::merge
