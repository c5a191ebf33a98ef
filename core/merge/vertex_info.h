// Each merged vertex described by the measurements around it (VertexInfo, issues 34 and 35): the
// colour of the nearest scan point that has one, and the distance to the nearest scan point — so
// that an exported mesh shows the scanners' colour, and where its surface was measured and where
// the field only interpolated it (a filled hole, a wide far-range triangle).
#pragma once

#include <cstddef>

#include "core/common/expected.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_io.h"
#include "core/merge/range_patches.h"

namespace scanreg::merge {

// Describes mesh->vertices[mesh->info.size() ..] (relative to patches.origin, which must be the
// mesh's) from the patches' points (k-d trees over them, nanoflann): the nearest within kMaxGapVoxels
// voxels (beyond: gap kMaxGapVoxels voxels, colour from no point). Sets mesh->coloured when a scan
// of the patches has colour. In parallel over vertices.
void DescribeVertices(const RangePatches& patches, double voxel_m, Mesh* mesh);

// Vertices farther than this from every scan point lie on interpolated surface ("filled"): half a
// voxel beyond the farthest a vertex of a measured surface lies from the measurement nearest it.
inline double FilledGap(double voxel_m) { return 1.5 * voxel_m; }
// The least gap of a vertex that only filled values made (Mesh::on_filled), however near a scan point:
// half a voxel beyond FilledGap, so that a threshold at 1.5 voxels in another program (CloudCompare's
// scalar field "gap", printed to a few decimals) finds it.
inline double MarkedGap(double voxel_m) { return 2.0 * voxel_m; }
// The described vertices of `mesh` beyond FilledGap (0 when not described).
Expected<std::size_t> CountInterpolated(const MeshSource& mesh, double voxel_m);

}  // namespace scanreg::merge
