// A merged mesh small enough to show (issue 13: the desktop previews a merge of any size). A mesh
// within the triangle budget is shown whole; a larger one is simplified by vertex clustering as it
// streams from its source (MeshSpill or memory): the vertices of each cubic cell become their mean,
// triangles whose corners fall in fewer than three cells vanish, and repeated triangles are dropped.
// The preview's memory is its own plus 4 bytes a source vertex.
#pragma once

#include <cstddef>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/merge/mesh.h"
#include "core/merge/mesh_io.h"

namespace scanreg::merge {

struct MeshPreview {
  Mesh mesh;
  double cell_m = 0.0;  // the clustering cell; 0: the whole mesh
};

// At most max_triangles (> 0) triangles of `source`. voxel_m: the merge's voxel (the source's edge
// length), from which the first cell is sized; the cell doubles until the preview fits. Errors: the
// source's read errors, cancelled (kCancelled).
Expected<MeshPreview> PreviewMesh(const MeshSource& source, std::size_t max_triangles, double voxel_m,
                                  const CancelToken& cancel);

}  // namespace scanreg::merge
