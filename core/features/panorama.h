// Reflectance panoramas: the image W §2 runs SIFT on. One pixel per scan cell, row 0 on top
// (highest elevation), column c = scan column c.
#pragma once

#include <opencv2/core.hpp>

#include "core/geometry/scan.h"

namespace scanreg {

struct PanoramaOptions {
  double low_percentile = 1.0;    // percent of valid cells mapped to grey 1 (and below)
  double high_percentile = 99.0;  // percent of valid cells mapped to grey 255 (and above)

  Status Validate() const;
};

// CV_8UC1, scan.rows x scan.cols. Empty cells are 0; valid cells 1..255 after a linear contrast
// stretch between the given percentiles of the valid reflectances (robust to a few outliers).
// An empty scan (no valid cell) gives an all-zero image.
cv::Mat ReflectancePanorama(const Scan& scan, const PanoramaOptions& options = {});

}  // namespace scanreg
