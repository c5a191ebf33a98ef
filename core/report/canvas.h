// Drawing helpers shared by the report's pictures (OpenCV, BGR images): the link status colours,
// text placement and dashed lines.
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "core/io/project.h"

namespace scanreg::report {

// Link colours as the GUI's network panel shows them: green ok, orange weak, red failed.
cv::Scalar StatusColor(io::LinkStatus status);
const cv::Scalar kInk(40, 40, 40);
const cv::Scalar kGrid(225, 225, 225);
const cv::Scalar kWhite(255, 255, 255);

// Hershey simplex text; anchor is the text's centre (Centered) or its left baseline (Text).
void DrawText(cv::Mat& image, const std::string& text, cv::Point left_baseline, double scale, const cv::Scalar& color,
              int thickness = 1);
void DrawTextCentered(cv::Mat& image, const std::string& text, cv::Point center, double scale, const cv::Scalar& color,
                      int thickness = 1);
cv::Size TextSize(const std::string& text, double scale, int thickness = 1);

// A line drawn as dashes of `dash` pixels separated by `gap` pixels (1 px without antialiasing: crisp).
void DrawDashedLine(cv::Mat& image, cv::Point2d a, cv::Point2d b, const cv::Scalar& color, int thickness, double dash,
                    double gap);

// PNG bytes of the image, written atomically to path; errors name the file.
Status WritePng(const cv::Mat& image, const std::filesystem::path& path);

}  // namespace scanreg::report
