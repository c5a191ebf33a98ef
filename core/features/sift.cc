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

// An 8-bit image at half size: each pixel `combine` of a 2 x 2 block (an odd last row or column
// counts twice). Pixel (r, c) of the result is centred on (2c + 0.5, 2r + 0.5) of the input.
template <typename Combine>
cv::Mat Halve(const cv::Mat& image, Combine combine) {
  const int rows = (image.rows + 1) / 2, cols = (image.cols + 1) / 2;
  cv::Mat out(rows, cols, CV_8UC1);
  for (int r = 0; r < rows; ++r) {
    const std::uint8_t* a = image.ptr<std::uint8_t>(2 * r);
    const std::uint8_t* b = image.ptr<std::uint8_t>(std::min(2 * r + 1, image.rows - 1));
    std::uint8_t* o = out.ptr<std::uint8_t>(r);
    for (int c = 0; c < cols; ++c) {
      const int c0 = 2 * c, c1 = std::min(2 * c + 1, image.cols - 1);
      o[c] = static_cast<std::uint8_t>(combine(a[c0], a[c1], b[c0], b[c1]));
    }
  }
  return out;
}

// The panorama at half size: the rounded mean of each block.
cv::Mat HalveImage(const cv::Mat& image) {
  return Halve(image, [](int a, int b, int c, int d) { return (a + b + c + d + 2) / 4; });
}

// The valid-cell mask at half size: a pixel is valid only when all four cells under it are.
cv::Mat HalveMask(const cv::Mat& mask) {
  return Halve(mask, [](int a, int b, int c, int d) { return a & b & c & d; });
}

}  // namespace

int SiftImageScale(const Scan& scan, const SiftOptions& options) {
  const double max_step = options.half_size_max_step_deg * kPi / 180.0;
  if (!(max_step > 0) || !scan.single_viewpoint || scan.angles.empty() || scan.rows < 2 || scan.cols < 2 ||
      static_cast<int>(scan.angles.azimuth.size()) != scan.cols ||
      static_cast<int>(scan.angles.elevation.size()) != scan.rows)
    return 1;
  double az = 0;  // the mean column step, the seam's wrap left out
  for (int c = 0; c + 1 < scan.cols; ++c)
    az += std::abs(std::remainder(static_cast<double>(scan.angles.azimuth[c + 1]) - scan.angles.azimuth[c], 2 * kPi));
  az /= scan.cols - 1;
  const double el =
      std::abs(static_cast<double>(scan.angles.elevation.back()) - scan.angles.elevation.front()) / (scan.rows - 1);
  return std::isfinite(az) && std::isfinite(el) && az > 0 && el > 0 && az <= max_step && el <= max_step ? 2 : 1;
}

namespace {

// The strips of a rows x cols detection image (SiftOptions::strip_pixels).
int StripsOf(int rows, int cols, const SiftOptions& options) {
  const std::int64_t pixels = std::int64_t(std::max(rows, 0)) * std::max(cols, 0);
  if (options.strip_pixels <= 0 || pixels <= options.strip_pixels) return 1;
  const int strips = int((pixels + options.strip_pixels - 1) / options.strip_pixels);
  return std::clamp(strips, 1, std::max(1, cols / (2 * kStripOverlapPx)));  // strips wider than their overlaps
}

}  // namespace

int SiftStrips(const Scan& scan, const SiftOptions& options) {
  const int scale = SiftImageScale(scan, options);
  return StripsOf((scan.rows + scale - 1) / scale, (scan.cols + scale - 1) / scale, options);
}

std::size_t SiftStripPixels(const Scan& scan, const SiftOptions& options) {
  const int scale = SiftImageScale(scan, options);
  const int rows = (scan.rows + scale - 1) / scale, cols = (scan.cols + scale - 1) / scale;
  const int strips = StripsOf(rows, cols, options);
  if (strips == 1) return std::size_t(std::max(rows, 0)) * std::size_t(std::max(cols, 0));
  return std::size_t(rows) * std::size_t(cols / strips + 1 + 2 * kStripOverlapPx + kStripAlignPx);
}

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
  if (strip_pixels < 0) return bad("strip_pixels must be >= 0 (0 = whole), got " + std::to_string(strip_pixels));
  if (!(half_size_max_step_deg >= 0 && half_size_max_step_deg <= 10))
    return bad("half_size_max_step_deg must be in [0, 10] degrees (0 = always full size), got " +
               std::to_string(half_size_max_step_deg));
  return Status::Ok();
}

Expected<ScanFeatures> DetectFeatures(const Scan& scan, const SiftOptions& options) {
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = scan.Validate(); !s) return s.error();
  ScanFeatures out;
  out.rows = scan.rows;
  out.cols = scan.cols;
  if (scan.rows < 8 || scan.cols < 8) return out;  // too small for any SIFT keypoint

  // The detection image: the panorama, at half size for a finely sampled one (SiftImageScale).
  const int scale = SiftImageScale(scan, options);
  cv::Mat panorama = ReflectancePanorama(scan);
  cv::Mat mask(scan.rows, scan.cols, CV_8UC1);
  for (int r = 0; r < scan.rows; ++r) {
    auto* row = mask.ptr<std::uint8_t>(r);
    for (int c = 0; c < scan.cols; ++c) row[c] = scan.IsValid(r, c) ? 255 : 0;
  }
  if (scale == 2) {
    panorama = HalveImage(panorama);
    mask = HalveMask(mask);
  }
  const int cols = panorama.cols;

  const bool wrap = options.wrap_margin_px > 0 && CoversFullCircle(scan);
  const int margin = wrap ? std::min((options.wrap_margin_px + scale - 1) / scale, cols) : 0;
  cv::Mat image = wrap ? WrapPad(panorama, margin) : panorama;
  if (wrap) mask = WrapPad(mask, margin);
  // At half size a keypoint's full-size cell lies up to a cell beyond its half-size pixel's two, so
  // the mask erodes by one more full-size cell: the cells within mask_erosion_px stay valid.
  if (const int erosion = options.mask_erosion_px > 0 ? (options.mask_erosion_px + 2 * (scale - 1)) / scale : 0;
      erosion > 0) {
    const int k = 2 * erosion + 1;
    // Outside the image counts as valid: only empty cells erode the mask, not the image border.
    cv::erode(mask, mask, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)), cv::Point(-1, -1), 1,
              cv::BORDER_CONSTANT, cv::Scalar(255));
  }

  cv::Ptr<cv::SIFT> sift = cv::SIFT::create(0, options.octave_layers, options.contrast_threshold,
                                            options.edge_threshold, options.sigma);
  // Column strips of a large panorama, each with kStripOverlapPx of its neighbours' columns (or
  // the wrap padding), keeping the keypoints centred in its own columns: SIFT's pyramids are one
  // strip's, not the whole panorama's (issue 13: ~1.6 GB on a 10 M-pixel panorama).
  const int strips = SiftStrips(scan, options);
  std::vector<cv::KeyPoint> cv_keypoints;
  std::vector<cv::Mat> strip_descriptors(strips);
  std::vector<std::pair<int, int>> descriptor_of;  // per keypoint: its strip and row there
  for (int k = 0; k < strips; ++k) {
    const int c0 = int(std::int64_t(cols) * k / strips), c1 = int(std::int64_t(cols) * (k + 1) / strips);
    // A strip starts on a multiple of kStripAlignPx of the (padded) panorama, so that its octaves
    // sample the same pixels as the whole panorama's.
    const int a = strips > 1 ? std::max(0, (c0 + margin - kStripOverlapPx) / kStripAlignPx * kStripAlignPx) : 0;
    const int b = std::min(image.cols, c1 + margin + (strips > 1 ? kStripOverlapPx : margin));
    std::vector<cv::KeyPoint> found;
    cv::Mat& descriptors = strip_descriptors[k];
    sift->detectAndCompute(image.colRange(a, b), mask.colRange(a, b), found, descriptors);
    if (!found.empty() && (descriptors.type() != CV_32F || descriptors.cols != kSiftDescriptorSize))
      return MakeError(ErrorCode::kFailed, "SIFT on scan '" + scan.name + "' returned descriptors of an unexpected type");
    for (int i = 0; i < static_cast<int>(found.size()); ++i) {
      cv::KeyPoint kp = found[i];
      kp.pt.x += float(a);  // detection-image coordinates, padded
      kp.pt.x -= float(margin);  // and unpadded
      const int c = static_cast<int>(std::lround(kp.pt.x));
      if (c < c0 || c >= c1) continue;  // another strip's (or the padding's)
      // Back to the panorama's pixels. Half-size pixel (x, y) is centred on (2x + 0.5, 2y + 0.5), and
      // OpenCV reports positions a quarter of its input's pixel past the truth (it doubles the image
      // centre-aligned, then halves the coordinates): at half size that quarter is half a full-size
      // pixel, and the two cancel. (At full size the quarter pixel stays, as it always has.)
      kp.pt.x *= float(scale);
      kp.pt.y *= float(scale);
      kp.size *= float(scale);
      cv_keypoints.push_back(kp);
      descriptor_of.emplace_back(k, i);
    }
  }

  // Keep each keypoint once: only those whose centre lies in the original columns.
  std::vector<int> keep;
  keep.reserve(cv_keypoints.size());
  for (int i = 0; i < static_cast<int>(cv_keypoints.size()); ++i) {
    const int c = static_cast<int>(std::lround(cv_keypoints[i].pt.x));
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
    out.keypoints.push_back(Keypoint{kp.pt.x, kp.pt.y, kp.size, kp.angle, kp.response});
    const auto [strip, row] = descriptor_of[keep[k]];
    std::copy_n(strip_descriptors[strip].ptr<float>(row), kSiftDescriptorSize,
                out.descriptors.data() + k * kSiftDescriptorSize);
  }
  return out;
}

}  // namespace scanreg
