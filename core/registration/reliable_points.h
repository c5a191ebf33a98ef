// Reliable 3D points for 2D keypoints (W §4.1, SPEC §2 step 5): a confidence map over the
// organized scan, and bilinear interpolation of a keypoint's 3D point from its 4 raster
// neighbours, only where all four are valid and reliable.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg {

struct ReliabilityOptions {
  // Cells darker than this are unreliable (weak returns, mixed pixels). W names a minimum but
  // gives no number; 0.02 on the nominal [0, 1] reflectance scale drops near-empty returns only.
  float min_reflectance = 0.02f;
  // t_std (W §4.1): maximum standard deviation of range over a cell's 3x3 neighbourhood, metres.
  // Larger values mean a depth edge or mixed pixels.
  double max_range_std_m = 0.1;

  Status Validate() const;
};

// One byte per cell (row-major, like the scan): 1 = reliable. A cell is reliable when it is
// valid, its reflectance >= min_reflectance, all 9 cells of its 3x3 neighbourhood exist and are
// valid, and the (population) standard deviation of their ranges is <= max_range_std_m.
// Neighbourhoods cross the azimuth seam of a full 360° panorama (see WrapsAzimuth); otherwise the
// first/last column, like the first/last row, is unreliable. Returns all zeros for a scan whose
// arrays disagree with its size.
std::vector<std::uint8_t> ConfidenceMap(const Scan& scan, const ReliabilityOptions& options);

// True when scan.angles covers a full turn, so that column cols-1 neighbours column 0: the gap
// between the last and first azimuth is at most 1.5 mean column steps and the columns span more
// than pi.
bool WrapsAzimuth(const Scan& scan);

// The 3D point (scanner frame) at sub-pixel position u (column) and v (row), pixel centres at
// integers: bilinear interpolation of the 4 surrounding raster points. nullopt unless all four
// are valid and marked reliable in `confidence` (from ConfidenceMap; empty = only validity is
// checked) and lie inside the grid. On a full panorama (WrapsAzimuth) columns wrap, so u in
// (cols-1, cols) interpolates between the last and the first column, and u in [-0.5, 0) too.
std::optional<Eigen::Vector3f> InterpolatePoint(const Scan& scan, const std::vector<std::uint8_t>& confidence,
                                                float u, float v);

}  // namespace scanreg
