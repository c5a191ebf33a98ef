#include "core/report/canvas.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/common/atomic_file.h"

namespace scanreg::report {

cv::Scalar StatusColor(io::LinkStatus status) {
  switch (status) {
    case io::LinkStatus::kOk:
      return {60, 160, 40};
    case io::LinkStatus::kWeak:
      return {0, 140, 255};
    case io::LinkStatus::kFailed:
      return {40, 40, 220};
  }
  return {40, 40, 220};
}

void DrawText(cv::Mat& image, const std::string& text, cv::Point left_baseline, double scale, const cv::Scalar& color,
              int thickness) {
  cv::putText(image, text, left_baseline, cv::FONT_HERSHEY_SIMPLEX, scale, color, thickness, cv::LINE_AA);
}

cv::Size TextSize(const std::string& text, double scale, int thickness) {
  int baseline = 0;
  return cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
}

void DrawTextCentered(cv::Mat& image, const std::string& text, cv::Point center, double scale, const cv::Scalar& color,
                      int thickness) {
  const cv::Size size = TextSize(text, scale, thickness);
  DrawText(image, text, {center.x - size.width / 2, center.y + size.height / 2}, scale, color, thickness);
}

void DrawDashedLine(cv::Mat& image, cv::Point2d a, cv::Point2d b, const cv::Scalar& color, int thickness, double dash,
                    double gap) {
  const double length = cv::norm(b - a);
  if (length < 1e-9) return;
  const cv::Point2d step = (b - a) / length;
  for (double s = 0; s < length; s += dash + gap) {
    const double e = std::min(s + dash, length);
    cv::line(image, a + step * s, a + step * e, color, thickness, thickness > 1 ? cv::LINE_AA : cv::LINE_8);
  }
}

Status WritePng(const cv::Mat& image, const std::filesystem::path& path) {
  std::vector<uchar> png;
  if (image.empty() || !cv::imencode(".png", image, png)) {
    return MakeError(ErrorCode::kIoError, path.string() + ": the picture could not be encoded as PNG");
  }
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(std::string_view(reinterpret_cast<const char*>(png.data()), png.size())); !s) return s;
  return file.Commit();
}

}  // namespace scanreg::report
