// The scan network as a top view (x right, y up) at the registered scanner positions: nodes
// labelled with the scan names (the root ringed), the scan-order tree drawn thick, every link
// coloured by status (green ok, orange weak, red failed, dashed), loop checks thin and dotted,
// unregistered scans in a strip below the map, a scale bar and a legend.
#pragma once

#include <opencv2/core.hpp>

#include "core/io/project.h"

namespace scanreg::report {

cv::Mat DrawScanNetwork(const io::Project& project);

}  // namespace scanreg::report
