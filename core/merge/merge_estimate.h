// What a merge will take, known before it starts (issue 16 item 2): the field's blocks counted from
// the scans' points the way ComputeField allocates them, and the memory and time that follow. A
// merge whose estimate exceeds the memory budget is refused with the voxel that would fit.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"
#include "core/merge/merge_options.h"

namespace scanreg::merge {

struct MergeEstimate {
  std::size_t points = 0;     // valid points within the maximum range
  std::size_t blocks = 0;     // 8^3-voxel blocks of the field
  bool extrapolated = false;  // the count passed its cap: counted at a coarser voxel and scaled
  std::size_t bytes = 0;      // peak memory beyond the loaded scans
  std::size_t disk_bytes = 0;  // the mesh's temporary files, when it is spilled to disk (MeshSpill);
                               // the output file takes about 1.4 times as much again
  double seconds = 0.0;       // wall time with this machine's threads

  // "about 2.1 GB and 40 s (180,000 blocks of 8^3 voxels)"
  std::string Describe() const;
};

// cap_blocks: stop counting there (the estimate is then extrapolated from a coarser voxel).
// strides: the scans are previews (pipeline::ScanPreview) — every strides[i]-th row and column of
// the scan that will be merged — so scan i's points count strides[i]^2 times (empty: all 1).
// mesh_on_disk: the mesh is spilled (MeshSpill): its bytes are disk_bytes, not memory.
MergeEstimate EstimateMerge(const std::vector<const Scan*>& scans, const MergeOptions& options,
                            std::size_t cap_blocks = 50'000'000, const std::vector<int>& strides = {},
                            bool mesh_on_disk = false);

// Three quarters of this machine's physical memory.
std::size_t DefaultMemoryBudget();

// Ok when the estimate fits options.memory_budget_bytes (0: DefaultMemoryBudget()); else an error
// with the estimate, the budget and the smallest voxel (and the largest maximum range) that fit.
Status CheckMergeFits(const std::vector<const Scan*>& scans, const MergeOptions& options, MergeEstimate* estimate,
                      const std::vector<int>& strides = {}, bool mesh_on_disk = false);

}  // namespace scanreg::merge
