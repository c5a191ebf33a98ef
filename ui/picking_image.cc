#include "ui/picking_image.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/features/panorama.h"

namespace scanreg::ui {

QImage PickingImage(const Scan& scan) {
  float lo_r = INFINITY, hi_r = -INFINITY;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) lo_r = std::min(lo_r, scan.reflectance[i]), hi_r = std::max(hi_r, scan.reflectance[i]);
  if (hi_r > lo_r) {
    const cv::Mat gray = ReflectancePanorama(scan);
    return QImage(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step), QImage::Format_Grayscale8).copy();
  }
  std::vector<float> ranges;
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) ranges.push_back(scan.points[i].norm());
  QImage image(scan.cols, scan.rows, QImage::Format_Grayscale8);
  image.fill(0);
  if (ranges.empty()) return image;
  std::sort(ranges.begin(), ranges.end());
  const float near = ranges[ranges.size() / 50], far = std::max(ranges[ranges.size() * 49 / 50], near + 1e-3f);
  for (int r = 0; r < scan.rows; ++r) {
    uchar* line = image.scanLine(r);
    for (int c = 0; c < scan.cols; ++c) {
      if (!scan.IsValid(r, c)) continue;
      const float t = std::clamp((scan.Point(r, c).norm() - near) / (far - near), 0.0f, 1.0f);
      line[c] = static_cast<uchar>(1 + 254 * (1 - t));
    }
  }
  return image;
}

std::optional<std::pair<int, int>> SnapToCell(const Scan& scan, QPointF pixel, int snap) {
  const int c0 = static_cast<int>(std::floor(pixel.x())), r0 = static_cast<int>(std::floor(pixel.y()));
  int best = -1;
  std::pair<int, int> cell;
  for (int r = std::max(0, r0 - snap); r <= std::min(scan.rows - 1, r0 + snap); ++r)
    for (int c = std::max(0, c0 - snap); c <= std::min(scan.cols - 1, c0 + snap); ++c) {
      const int d = (r - r0) * (r - r0) + (c - c0) * (c - c0);
      if (!scan.IsValid(r, c) || d > snap * snap || (best >= 0 && d >= best)) continue;
      best = d;
      cell = {r, c};
    }
  if (best < 0) return std::nullopt;
  return cell;
}

}  // namespace scanreg::ui
