// Trust without ground truth (issue 33): the multi-view fine step over every overlapping pair, and
// the checks that make "registered" mean verified. The project's consistency — the robust RMS of
// the point-to-plane residuals of every overlapping pair (core/registration/multiview.h) — is
// measured at the start poses and at the result:
//   - the multi-view step's poses are taken only when they are more consistent than the pairwise
//     result (the pose graph keeps each pair's own error; this removes it);
//   - a scan whose share is worse than at its start pose goes back to its start pose (a link that
//     disagrees with its other overlaps never moves it), the worst first, until none is;
//   - a result less consistent than the start as a whole is refused: every scan keeps its start pose;
//   - a scan is registered only when its share is near the scanner's noise, it overlaps a registered
//     scan, and its overlaps constrain every direction of its pose; otherwise its reason says which.
// Used where the start poses mean something (refinement from the current poses).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {

struct VerifyOptions {
  double cutoff_m = 0;        // a sample meets the other surface within this (the data's overlap distance)
  double scale_factor = 0.25;  // the bounded loss's scale, x cutoff_m
  double evidence_m = 0;      // the data's overlap distance: pairs overlap, and the multi-view step starts, within it
  double noise_m = 0;         // the scanner's range noise
  double min_overlap = 0.05;  // a pair overlaps from this share of samples on
  bool multiview = true;
  // A scan's share may reach this many times the noise (two noisy surfaces, sampling) and still be verified.
  double noise_factor = 4.0;
  // ... or this many times the median share of the registered scans (whichever is larger), and at
  // most half the cutoff.
  double spread_factor = 2.5;
  double min_conditioning = 1e-3;  // below: a direction of the pose is free (degenerate overlap)
};

// samples: per scan, its voxel samples in its own frame. `result` comes from the driver with the
// scans' start poses in scans[i].world_from_scan; it leaves with the poses taken, each scan's
// shares and conditioning, result->consistency, and unverified scans unregistered with the reason.
Status VerifyAgainstStart(const std::vector<Scan>& scans, const std::vector<std::vector<Eigen::Vector3d>>& samples,
                          const ScanOrderChoices& choices, const VerifyOptions& options, ProgressSink& progress,
                          const CancelToken& cancel, ProjectRegistration* result);

}  // namespace scanreg::pipeline
