#include "core/report/error_chart.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/report/canvas.h"

namespace scanreg::report {
namespace {

constexpr int kPanelHeight = 260;
constexpr int kLeft = 80, kRight = 20, kTop = 40, kBottom = 50;
const cv::Scalar kCoarse(230, 190, 140);  // light blue
const cv::Scalar kFine(140, 70, 20);      // dark blue

// Smallest "nice" axis top (1, 2, 2.5, 5 x 10^k) at or above value.
double AxisTop(double value) {
  if (!(value > 0)) return 1.0;
  const double p = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * p >= value) return m * p;
  return 10 * p;
}

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, v >= 100 ? "%.0f" : v >= 1 ? "%.1f" : "%.3g", v);
  return buf;
}

// One panel: values[i] = {coarse, fine}, negative = not available.
void DrawPanel(cv::Mat& image, int top, const std::string& title, const std::vector<std::string>& names,
               const std::vector<std::pair<double, double>>& values) {
  const int width = image.cols - kLeft - kRight;
  const int height = kPanelHeight - kTop - kBottom;
  double max_value = 0;
  for (const auto& v : values) max_value = std::max({max_value, v.first, v.second});
  const double axis = AxisTop(max_value);
  const int y0 = top + kTop + height;
  DrawText(image, title, {kLeft, top + 24}, 0.55, kInk, 1);
  for (int k = 0; k <= 4; ++k) {
    const int y = y0 - height * k / 4;
    cv::line(image, {kLeft, y}, {kLeft + width, y}, kGrid, 1);
    const std::string label = Number(axis * k / 4);
    DrawText(image, label, {kLeft - 8 - TextSize(label, 0.4).width, y + 5}, 0.4, kInk);
  }
  cv::line(image, {kLeft, y0}, {kLeft + width, y0}, kInk, 1);
  const int n = static_cast<int>(values.size());
  const double slot = double(width) / std::max(n, 1);
  const int bar = std::max(2, static_cast<int>(slot * 0.35));
  for (int i = 0; i < n; ++i) {
    const int x = kLeft + static_cast<int>(slot * i + slot / 2);
    const double v[2] = {values[i].first, values[i].second};
    if (v[0] < 0 && v[1] < 0) {
      DrawTextCentered(image, "n/a", {x, y0 - 12}, 0.4, cv::Scalar(150, 150, 150));
    }
    for (int k = 0; k < 2; ++k) {
      if (v[k] < 0) continue;
      const int h = std::max(1, static_cast<int>(std::round(height * v[k] / axis)));
      const int bx = k == 0 ? x - bar : x;
      cv::rectangle(image, cv::Rect(bx, y0 - h, bar, h), k == 0 ? kCoarse : kFine, cv::FILLED);
    }
    if (slot >= 30 || i % std::max(1, static_cast<int>(std::ceil(30 / slot))) == 0) {
      DrawTextCentered(image, names[i], {x, y0 + 16}, 0.4, kInk);
    }
  }
}

}  // namespace

cv::Mat DrawReferenceErrorChart(const std::vector<std::string>& names,
                                const std::vector<pipeline::ReferenceError>& errors) {
  const int n = static_cast<int>(errors.size());
  const int width = std::clamp(kLeft + kRight + 48 * n, 560, 1400);
  cv::Mat image(2 * kPanelHeight + 40, width, CV_8UC3, kWhite);
  std::vector<std::pair<double, double>> position(n), angle(n);
  for (int i = 0; i < n; ++i) {
    const pipeline::ReferenceError& e = errors[i];
    const bool coarse = e.available && e.has_coarse;
    position[i] = {coarse ? e.coarse_position_m * 1000 : -1, e.available ? e.position_m * 1000 : -1};
    angle[i] = {coarse ? e.coarse_angle_rad * 180 / M_PI : -1, e.available ? e.angle_rad * 180 / M_PI : -1};
  }
  DrawPanel(image, 0, "position error (mm)", names, position);
  DrawPanel(image, kPanelHeight, "angle error (degrees)", names, angle);
  const int y = 2 * kPanelHeight + 20;
  cv::rectangle(image, cv::Rect(kLeft, y - 10, 24, 14), kCoarse, cv::FILLED);
  DrawText(image, "after coarse registration", {kLeft + 32, y + 2}, 0.45, kInk);
  cv::rectangle(image, cv::Rect(kLeft + 280, y - 10, 24, 14), kFine, cv::FILLED);
  DrawText(image, "after fine registration", {kLeft + 312, y + 2}, 0.45, kInk);
  return image;
}

}  // namespace scanreg::report
