// Marching Cubes (Lorensen & Cline 1987, Bourke's tables) on the sparse grid: one vertex per grid
// edge crossing the zero level, shared by the cubes around that edge, so that a closed surface
// gives a watertight mesh. Cubes with an unknown corner produce nothing.
#pragma once

#include "core/merge/mesh.h"
#include "core/merge/sparse_grid.h"

namespace scanreg::merge {

Mesh ExtractMesh(const SparseGrid& grid);

}  // namespace scanreg::merge
