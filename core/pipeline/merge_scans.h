// Merging a project's registered scans into one mesh (SPEC §4), and writing it. The CLI and the
// GUI both run these.
#pragma once

#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/merge/merge.h"
#include "core/merge/merge_estimate.h"
#include "core/merge/merge_options.h"
#include "core/merge/mesh.h"

namespace scanreg::pipeline {

using merge::MergeEstimate;
using merge::MergeMethod;
using merge::MergeOptions;
using merge::MergeResult;
using merge::Mesh;

// Merges scans[i] where use[i] (all scans when `use` is empty); their world_from_scan must be the
// registered poses. Errors: bad options (naming the option), no scan selected, no valid point
// (naming the scans), a merge estimated beyond options.memory_budget_bytes (with the voxel that
// fits; merge_estimate.h), cancelled (kCancelled; nothing is written anywhere).
// The scans are taken by value and the left-out points (moving objects, beyond the maximum range)
// marked invalid in them: a caller that loaded them for the merge moves them in (no second copy).
Expected<MergeResult> MergeScans(std::vector<Scan> scans, const std::vector<bool>& use,
                                 const MergeOptions& options, ProgressSink& progress, const CancelToken& cancel);

// The project's scans `which` (by index; registered) merged without holding them all (issue 13:
// merge memory bounded whatever the project's size): each is read from its file (the binary scan
// cache) when a step needs it, at most scan_budget_bytes of them resident — the estimate from the
// previews, the moving-object test scan by scan against its observers, a first pass for the
// extents, then each tile the cells that reach it. The same mesh as MergeScans on the loaded scans.
// Errors as MergeScans's, and a scan that cannot be read (naming it and its file).
// spill: the mesh goes there (merge::MergeScanSet), not into the result.
Expected<MergeResult> MergeProjectScans(const io::Project& project, const std::vector<int>& which,
                                        const MergeOptions& options, std::size_t scan_budget_bytes,
                                        ProgressSink& progress, const CancelToken& cancel,
                                        merge::MeshSpill* spill = nullptr);

// Merge options sized to the scans (issue 14: a default that finishes): the voxel starts from the
// data's scale — a thousandth of the scans' median extent, at least their point spacing, between
// 1 mm and options.voxel_m — and grows until the estimate (merge_estimate.h) takes at most
// max_seconds and half the memory budget (counts past 500 k blocks extrapolated). The range noise
// sigma shrinks in proportion when the voxel is sized below options.voxel_m, not below the scans'
// measured roughness (data_scale.h), never above options.sigma_m: the 12 mm that go with 2 cm
// voxels would blur a 20 cm object. *estimate: the estimate of the options returned.
// strides: the scans are previews (merge::EstimateMerge); the point spacing is the finest scan's.
MergeOptions SizedMergeOptions(const std::vector<const Scan*>& scans, MergeOptions options, double max_seconds,
                               MergeEstimate* estimate, const std::vector<int>& strides = {});

// Options sized to the project's scans `which` (SizedMergeOptions on their previews, with no time
// limit; only the memory budget coarsens the voxel): the voxel when size_voxel (to 0.1 mm), the
// range noise when size_sigma; the rest as given (scanreg-cli merge without --voxel / --sigma).
Expected<MergeOptions> SizeMergeToProject(const io::Project& project, const std::vector<int>& which,
                                          MergeOptions options, bool size_voxel, bool size_sigma,
                                          ProgressSink& progress, const CancelToken& cancel);

// Writes the mesh by extension: .ply (binary), .obj or .stl (binary); atomic. From a spill too.
Status WriteMesh(const std::filesystem::path& path, const Mesh& mesh);
Status WriteMesh(const std::filesystem::path& path, const merge::MeshSource& mesh);
// Writes the merged point cloud (the mesh's vertices: points on the merged surface) in world
// coordinates: a binary PLY of doubles (.ply) or LAS 1.4 at 0.1 mm (.las); atomic. Other extensions
// are an error.
Status WritePoints(const std::filesystem::path& path, const Mesh& mesh);
Status WritePoints(const std::filesystem::path& path, const merge::MeshSource& mesh);
// The checks WriteMesh and WritePoints make first (the extension), for callers to run before a
// long merge.
Status ValidateMeshPath(const std::filesystem::path& path);
Status ValidatePointsPath(const std::filesystem::path& path);

}  // namespace scanreg::pipeline
