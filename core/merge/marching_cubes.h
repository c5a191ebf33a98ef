// Marching Cubes (Lorensen & Cline 1987, Bourke's tables) on the sparse grid: one vertex per grid
// edge crossing the zero level, shared by the cubes around that edge, so that a closed surface
// gives a watertight mesh. Cubes with an unknown corner produce nothing.
#pragma once

#include <functional>
#include <unordered_map>

#include "core/merge/mesh.h"
#include "core/merge/sparse_grid.h"

namespace scanreg::merge {

Mesh ExtractMesh(const SparseGrid& grid);

// The same piece by piece (a tiled merge): each Add meshes the cubes whose lowest grid point lies in
// `own` (all when null), and a vertex on a grid edge that an earlier piece already holds is shared,
// so that the pieces join without duplicate vertices or cracks. Every piece's grid has the same
// origin and voxel, and its values at the grid points that cubes in `own` touch are final.
class MeshBuilder {
 public:
  void Add(const SparseGrid& grid, const SparseGrid::Bounds* own = nullptr);
  // Forgets the vertices of grid edges between cubes all meshed already — done(i, j): every cube
  // whose lowest grid point is (i, j, any k) — so that only a tiled merge's border with the tiles
  // to come stays in memory, not every tile border so far.
  void Forget(const std::function<bool(int i, int j)>& done);
  Mesh& mesh() { return mesh_; }
  // The vertices and triangles added since the last Take (triangles index all vertices added so far,
  // taken or not: a caller that streams the mesh out appends the pieces in order).
  Mesh Take();

 private:
  struct EdgeKey {
    int i, j, k, axis;  // the edge from grid point (i, j, k) one step along axis
    bool operator==(const EdgeKey& o) const { return i == o.i && j == o.j && k == o.k && axis == o.axis; }
  };
  struct EdgeKeyHash {
    std::size_t operator()(const EdgeKey& e) const {
      return BlockKeyHash()(BlockKey{e.i, e.j, e.k}) * 4 + std::size_t(e.axis);
    }
  };
  Mesh mesh_;
  int flushed_ = 0;  // vertices taken
  std::unordered_map<EdgeKey, int, EdgeKeyHash> vertex_of_;
};

}  // namespace scanreg::merge
