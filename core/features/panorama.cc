#include "core/features/panorama.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace scanreg {

Status PanoramaOptions::Validate() const {
  if (!(low_percentile >= 0.0 && low_percentile < high_percentile && high_percentile <= 100.0))
    return MakeError(ErrorCode::kInvalidArgument, "panorama: percentiles must satisfy 0 <= low < high <= 100 (got " +
                                                      std::to_string(low_percentile) + ", " +
                                                      std::to_string(high_percentile) + ")");
  return Status::Ok();
}

cv::Mat ReflectancePanorama(const Scan& scan, const PanoramaOptions& options) {
  cv::Mat image(scan.rows, scan.cols, CV_8UC1, cv::Scalar(0));
  std::vector<float> values;
  values.reserve(scan.size());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) values.push_back(scan.reflectance[i]);
  if (values.empty()) return image;
  const double lo_p = std::clamp(options.low_percentile, 0.0, 100.0);
  const double hi_p = std::clamp(std::max(options.high_percentile, lo_p), 0.0, 100.0);
  auto percentile = [&](double p) {
    const auto k = static_cast<std::size_t>(std::lround(p / 100.0 * (values.size() - 1)));
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return static_cast<double>(values[k]);
  };
  const double lo = percentile(lo_p);
  double hi = percentile(hi_p);
  if (hi <= lo) hi = lo + 1e-6;
  const double scale = 254.0 / (hi - lo);
  for (int r = 0; r < scan.rows; ++r) {
    auto* row = image.ptr<std::uint8_t>(r);
    for (int c = 0; c < scan.cols; ++c) {
      const std::size_t i = scan.Index(r, c);
      if (!scan.valid[i]) continue;
      const double g = 1.0 + (scan.reflectance[i] - lo) * scale;
      row[c] = static_cast<std::uint8_t>(std::clamp(std::lround(g), 1L, 255L));
    }
  }
  return image;
}

}  // namespace scanreg
