// Defaults that fit the data (issue 11, item 6). Every length of the registration that the user
// did not set (0 in RegisterOptions) comes from the scans: the range noise from their local plane
// residuals, the overlap distance d from the noise and the point spacing, and every other length as
// a multiple of d — the multiples that street scans measured best with (d = 0.10 m there), so a
// 20 cm object gets millimetres and a 200 m street decimetres from the same rules.
#pragma once

#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_options.h"
#include "core/registration/data_scale.h"

namespace scanreg::pipeline {

// Medians over the scans of core/registration/data_scale.h.
struct ProjectScale {
  double spacing_m = 0, extent_m = 0, noise_m = 0;
  double geometric_voxel_m = 0;  // median over the scans of SuggestVoxel's rule (FPFH samples)
};
ProjectScale MeasureProjectScale(const std::vector<const Scan*>& scans);
ProjectScale MeasureProjectScale(const std::vector<DataScale>& scans);

// The overlap distance of a project's data: max(8 x noise, 2 x spacing, extent / 100) — a sample of
// a surface seen by both scans lies within it of the other's samples (noise on both sides, sampling
// gaps), and it stays a small fraction of the scene. Streets (median extent ~10 m) get 0.10 m, the
// value measured best there: larger ones let wrong plan-view poses overlap nearly as well (10 m
// stations at 1000x250: 0.10 m registers 6/6, 0.12-0.17 m 3/6).
double DataOverlapDistance(const ProjectScale& scale);

// o with every unset length filled from noise_m and the overlap distance d (both > 0): o's own
// noise and d when set, else these.
RegisterOptions WithLengths(RegisterOptions o, double noise_m, double overlap_distance_m);

// o with every unset length resolved from the scans, the geometric features' voxel too (each scan
// measured once, only when something is unset; the choices are logged). Errors when the scans give no scale (fewer than 20 valid points).
// *measured (optional): the scale, when it was measured.
Expected<RegisterOptions> ResolveLengths(const RegisterOptions& o, const std::vector<const Scan*>& scans,
                                         ProjectScale* measured = nullptr);
// The same from each scan's MeasureDataScale, taken one scan at a time (scans not all in memory);
// `scales` is used only when NeedsScale(o).
bool NeedsScale(const RegisterOptions& o);
Expected<RegisterOptions> ResolveLengthsFromScales(const RegisterOptions& o, const std::vector<DataScale>& scales,
                                         ProjectScale* measured = nullptr);

// How far apart the scans' current poses are (refinement from current poses): over every pair of
// which at least half of the child's points lie within reach (extent / 3) of the parent's surface,
// the largest 2 x median distance of those points — misalignment, not sampling, dominates it; d
// (the data's overlap distance) when the poses agree.
double StartDistance(const std::vector<const Scan*>& scans, double d, double extent_m);

}  // namespace scanreg::pipeline
