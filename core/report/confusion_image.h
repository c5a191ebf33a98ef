// The confusion matrix C (W §2 step 3) as a heat map with the counts: rows and columns in scan
// order, off-diagonal cells from white (no match) to deep blue (the most matches off the
// diagonal), the diagonal (features per scan) in grey.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace scanreg::report {

// names: one per row of confusion. Counts are printed when the cells are large enough (up to
// about 25 scans); above that the colours alone show the structure.
cv::Mat DrawConfusionHeatMap(const Eigen::MatrixXi& confusion, const std::vector<std::string>& names);

}  // namespace scanreg::report
