#include "core/features/sift.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/features/panorama.h"

namespace scanreg {
namespace {

constexpr double kPi = 3.14159265358979323846;

// True when the columns cover the full circle (the panorama's left and right edges meet).
bool CoversFullCircle(const Scan& scan) {
  const auto& az = scan.angles.azimuth;
  if (scan.angles.empty() || static_cast<int>(az.size()) != scan.cols || scan.cols < 8) return false;
  double total = 0;
  for (int c = 0; c + 1 < scan.cols; ++c) {
    double d = static_cast<double>(az[c + 1]) - az[c];
    d = std::remainder(d, 2 * kPi);  // wrap to [-pi, pi]
    total += d;
  }
  const double step = total / (scan.cols - 1);
  return std::abs(total + step) >= 350.0 * kPi / 180.0;
}

cv::Mat WrapPad(const cv::Mat& image, int margin) {
  cv::Mat padded;
  cv::copyMakeBorder(image, padded, 0, 0, margin, margin, cv::BORDER_WRAP);
  return padded;
}

}  // namespace

Status SiftOptions::Validate() const {
  auto bad = [](const std::string& what) {
    return MakeError(ErrorCode::kInvalidArgument, "SIFT options: " + what);
  };
  if (max_features < 0) return bad("max_features must be >= 0 (0 = all), got " + std::to_string(max_features));
  if (!(contrast_threshold > 0 && contrast_threshold < 1))
    return bad("contrast_threshold must be in (0, 1), got " + std::to_string(contrast_threshold));
  if (!(edge_threshold > 1)) return bad("edge_threshold must be > 1, got " + std::to_string(edge_threshold));
  if (!(sigma > 0 && sigma < 10)) return bad("sigma must be in (0, 10) pixels, got " + std::to_string(sigma));
  if (octave_layers < 1 || octave_layers > 10)
    return bad("octave_layers must be in [1, 10], got " + std::to_string(octave_layers));
  if (mask_erosion_px < 0 || mask_erosion_px > 50)
    return bad("mask_erosion_px must be in [0, 50], got " + std::to_string(mask_erosion_px));
  if (wrap_margin_px < 0 || wrap_margin_px > 1000)
    return bad("wrap_margin_px must be in [0, 1000], got " + std::to_string(wrap_margin_px));
  return Status::Ok();
}

Expected<ScanFeatures> DetectFeatures(const Scan& scan, const SiftOptions& options) {
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = scan.Validate(); !s) return s.error();
  ScanFeatures out;
  out.rows = scan.rows;
  out.cols = scan.cols;
  if (scan.rows < 8 || scan.cols < 8) return out;  // too small for any SIFT keypoint

  const cv::Mat panorama = ReflectancePanorama(scan);
  cv::Mat mask(scan.rows, scan.cols, CV_8UC1);
  for (int r = 0; r < scan.rows; ++r) {
    auto* row = mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < scan.cols; ++c) row[c] = scan.IsValid(r, c) ? 255 : 0;
  }

  const bool wrap = options.wrap_margin_px > 0 && CoversFullCircle(scan);
  const int margin = wrap ? std::min(options.wrap_margin_px, scan.cols) : 0;
  cv::Mat image = wrap ? WrapPad(panorama, margin) : panorama;
  if (wrap) mask = WrapPad(mask, margin);
  if (options.mask_erosion_px > 0) {
    const int k = 2 * options.mask_erosion_px + 1;
    // Outside the image counts as valid: only empty cells erode the mask, not the image border.
    cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)), cv::Point(-1, -1), 1,
              cv::BORDER_CONSTANT, cv::Scalar(255));
  }

  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(0, options.octave_layers, options.contrast_threshold,
                                            options.edge_threshold, options.sigma);
  std::vector<cv::KeyPoint> cv_keypoints;
  cv::Mat cv_descriptors;
  sift->detectAndCompute(image, mask, cv_keypoints, cv_descriptors);
  if (!cv_keypoints.empty() && (cv_descriptors.type() != CV_32F || cv_descriptors.cols != kSiftDescriptorSize))
    return MakeError(ErrorCode::kFailed, "SIFT on scan '" + scan.name + "' returned descriptors of an unexpected type");

  // Keep each keypoint once: only those whose centre lies in the original columns.
  std::vector<int> keep;
  keep.reserve(cv_keypoints.size());
  for (int i = 0; i < static_cast<int>(cv_keypoints.size()); ++i) {
    const float u = cv_keypoints[i].pt.x - margin;
    const int c = static_cast<int>(std::lround(u));
    const int r = static_cast<int>(std::lround(cv_keypoints[i].pt.y));
    if (c < 0 || c >= scan.cols || r < 0 || r >= scan.rows) continue;
    if (!scan.IsValid(r, c)) continue;  // the mask already ensures this; kept as a guarantee
    keep.push_back(i);
  }
  auto key_less = [&](int a, int b) {
    const cv::KeyPoint& ka = cv_keypoints[a];
    const cv::KeyPoint& kb = cv_keypoints[b];
    if (ka.response != kb.response) return ka.response > kb.response;
    if (ka.pt.y != kb.pt.y) return ka.pt.y < kb.pt.y;
    if (ka.pt.x != kb.pt.x) return ka.pt.x < kb.pt.x;
    return a < b;
  };
  std::sort(keep.begin(), keep.end(), key_less);
  if (options.max_features > 0 && static_cast<int>(keep.size()) > options.max_features)
    keep.resize(options.max_features);

  out.keypoints.reserve(keep.size());
  out.descriptors.resize(keep.size() * kSiftDescriptorSize);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const cv::KeyPoint& kp = cv_keypoints[keep[k]];
    out.keypoints.push_back(Keypoint{kp.pt.x - margin, kp.pt.y, kp.size, kp.angle, kp.response});
    std::copy_n(cv_descriptors.ptr<float>(keep[k]), kSiftDescriptorSize,
                out.descriptors.data() + k * kSiftDescriptorSize);
  }
  return out;
}

}  // namespace scanreg
