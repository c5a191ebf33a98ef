// The lengths a scan's data sets (issue 11, item 6): its point spacing, its size and its noise,
// measured from the points alone, so defaults fit a 20 cm object and a 200 m street alike.
#pragma once

#include "core/geometry/scan.h"

namespace scanreg {

struct DataScale {
  double spacing_m = 0;  // median distance between neighbouring points at full resolution
  double extent_m = 0;   // median distance of the points from their centroid
  // Noise: the median RMS distance of a point's neighbourhood (16 nearest) from its best-fit plane,
  // corrected for the plane's fit to the same points. On curved or rough surfaces it includes their
  // roughness — an upper bound of the range noise, which is what the thresholds need.
  double noise_m = 0;
  bool ok() const { return spacing_m > 0 && extent_m > 0; }
};

// From up to ~100,000 points of the scan (evenly thinned; the spacing is corrected for the
// thinning). A scan with fewer than 20 valid points gives a DataScale that is not ok().
DataScale MeasureDataScale(const Scan& scan);

}  // namespace scanreg
