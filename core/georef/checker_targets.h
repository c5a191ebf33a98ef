// Checkerboard targets found in a scan's reflectance panorama (issue 15, item 1): black-and-white
// boards of four squares meeting at the centre, stuck on walls or on tripods.
//
// 1. Candidates: every cell gets a checker response from a ring of 16 reflectance samples around
//    it, a ring of a fixed metric radius (0.3 of the pattern) whatever the range (the ChESS
//    response, Bennett and Lasenby 2014: opposite samples alike, neighbouring quarters unlike, the
//    centre at the ring's mean). Local maxima above the contrast threshold are candidates.
// 2. The plane: a least-squares plane through the points around the candidate (outliers removed).
// 3. The centre on that plane: each cell's line of sight (exact: the encoders, not the noisy range)
//    meets the plane at a point of the board; the reflectance there is fitted with the pattern
//    model a + b erf(x'/s) erf(y'/s), x', y' the board's coordinates about the centre turned by
//    the pattern's angle, s the edge blur of the beam's Gaussian footprint (Levenberg-Marquardt, four
//    starting angles). Every cell near an edge returns a grey that places the edge to a fraction
//    of a cell, so the centre is found to a small fraction of the cell spacing.
// A fit is kept when its contrast, residual, edge sharpness, four alternating quarters and the
// centre's standard deviation (from the fit's covariance and the plane's) pass.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::georef {

struct CheckerTargetOptions {
  double size_m = 0.2;        // side of the 2 x 2 pattern (the four squares together)
  double max_range_m = 40.0;  // farther boards are too few cells to place
  double min_contrast = 0.08;  // reflectance difference between the light and the dark squares at least
  int min_points = 24;         // cells on the pattern used by the fit
  double max_sigma_m = 0.003;  // the centre's standard deviation at most
  double max_plane_rms_m = 0.02;  // the board and what is round it must be flat to this

  Status Validate() const;
};

struct DetectedChecker {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // scanner frame, metres
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  // the board's normal, towards the scanner
  double sigma_m = 0;    // standard deviation of the centre (in the board and across it)
  double contrast = 0;   // light minus dark reflectance
  double rms = 0;        // RMS of the reflectance residuals of the pattern fit
  int points = 0;        // cells on the pattern used by the fit
};

// Boards sorted by range. An empty list is not an error (no board in the scan; a scan without
// reflectance has none). Errors: bad options, a scan that is not an organized grid, cancel.
Expected<std::vector<DetectedChecker>> DetectCheckerTargets(const Scan& scan, const CheckerTargetOptions& options,
                                                            const CancelToken& cancel);

// The board nearest a cell the user clicked: the strongest checker response within search_cells of
// (row, col), then the fit above. None when no board passes there.
std::optional<DetectedChecker> FitCheckerTargetAt(const Scan& scan, int row, int col, int search_cells,
                                                  const CheckerTargetOptions& options);

}  // namespace scanreg::georef
