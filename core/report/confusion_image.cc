#include "core/report/confusion_image.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

#include "core/common/skipped_pair.h"
#include "core/report/canvas.h"

namespace scanreg::report {

cv::Mat DrawConfusionHeatMap(const Eigen::MatrixXi& confusion, const std::vector<std::string>& names) {
  const int n = static_cast<int>(confusion.rows());
  const int cell = std::clamp(1000 / std::max(n, 1), 10, 64);
  const bool counts = cell >= 38;
  int label_width = 0;
  for (const std::string& name : names) label_width = std::max(label_width, TextSize(name, 0.5).width);
  const int left = label_width + 16, top = label_width + 16, margin = 12;
  cv::Mat image(top + n * cell + margin, left + n * cell + margin, CV_8UC3, kWhite);

  int max_off = 1;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (i != j) max_off = std::max(max_off, confusion(i, j));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const cv::Rect r(left + j * cell, top + i * cell, cell, cell);
      cv::Scalar fill(210, 210, 210);
      bool dark = false;
      const bool skipped = i != j && confusion(i, j) == kSkippedPair;
      if (skipped) {
        fill = cv::Scalar(240, 240, 240);  // not matched: pale grey, a dash
      } else if (i != j) {
        const double f = std::clamp(double(confusion(i, j)) / max_off, 0.0, 1.0);
        fill = cv::Scalar(255, 255 * (1.0 - 0.6 * f), 255 * (1.0 - 0.8 * f));  // BGR: white -> deep blue
        dark = f > 0.6;
      }
      cv::rectangle(image, r, fill, cv::FILLED);
      cv::rectangle(image, r, cv::Scalar(190, 190, 190), 1);
      if (counts) {
        const std::string text = skipped ? "-" : std::to_string(confusion(i, j));
        const double scale = std::min(0.45, 0.45 * (cell - 6) / std::max(TextSize(text, 0.45).width, 1));
        DrawTextCentered(image, text, {r.x + cell / 2, r.y + cell / 2}, scale, dark ? kWhite : kInk);
      }
    }
  }
  // Row labels on the left, column labels written upwards above the columns.
  for (int i = 0; i < n && i < static_cast<int>(names.size()); ++i) {
    const cv::Size s = TextSize(names[i], 0.5);
    DrawText(image, names[i], {left - 8 - s.width, top + i * cell + cell / 2 + s.height / 2}, 0.5, kInk);
    cv::Mat label(s.height + 8, s.width + 4, CV_8UC3, kWhite);
    DrawText(label, names[i], {2, s.height + 2}, 0.5, kInk);
    cv::Mat up;
    cv::rotate(label, up, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int x = left + i * cell + (cell - up.cols) / 2;
    const int y = top - 6 - up.rows;
    if (x >= 0 && y >= 0 && x + up.cols <= image.cols) up.copyTo(image(cv::Rect(x, y, up.cols, up.rows)));
  }
  return image;
}

}  // namespace scanreg::report
