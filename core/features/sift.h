// SIFT keypoints and descriptors on a scan's reflectance panorama (W §2 step 1, SPEC §2.1).
#pragma once

#include <cstdint>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"

namespace scanreg {

inline constexpr int kSiftDescriptorSize = 128;
// Columns of overlap each side of a strip of a panorama detected in strips (SiftOptions::strip_pixels).
inline constexpr int kStripOverlapPx = 128;
inline constexpr int kStripAlignPx = 64;

// A keypoint in panorama pixel coordinates. Pixel (row r, column c) has its centre at
// (u, v) = (c, r) (OpenCV convention). The nearest cell (round(v), round(u)) is always inside the
// grid and valid, i.e. u and v are in [-0.5, cols - 0.5) and [-0.5, rows - 0.5).
struct Keypoint {
  float u = 0;         // column (azimuth direction), pixels
  float v = 0;         // row (elevation direction, 0 = highest elevation), pixels
  float size = 0;      // diameter of the meaningful neighbourhood, pixels
  float angle = 0;     // orientation, degrees in [0, 360) (OpenCV convention)
  float response = 0;  // DoG contrast; larger = stronger
};

struct SiftOptions {
  // Defaults are Lowe 2004 / OpenCV's, which W uses unchanged.
  int max_features = 0;             // keep the strongest N (by response); 0 = all
  double contrast_threshold = 0.04;  // DoG contrast threshold (OpenCV units, image in [0, 1] / octave layers)
  double edge_threshold = 10;       // principal-curvature ratio limit for edge-like extrema
  double sigma = 1.6;               // pixels: Gaussian blur of the base octave
  int octave_layers = 3;            // DoG layers per octave
  int mask_erosion_px = 2;          // pixels: valid-cell mask eroded by this; drops keypoints at the sky cut
  int wrap_margin_px = 48;          // pixels: panorama padded by this from the other side (360° seam); 0 = off
  // A panorama of more pixels is detected in column strips of about this many, each with
  // kStripOverlapPx columns of its neighbours: SIFT's memory (~160 bytes a pixel) is one strip's
  // (issue 13: ~1.6 GB on a 10 M-pixel panorama). 0: always whole. The paper's 3000 x 750 is whole.
  std::int64_t strip_pixels = 2'500'000;
  // A panorama seen from one spot whose cells are at most this many degrees apart in both
  // directions is detected at half size (2 x 2 cells averaged), its keypoints mapped back to
  // full-size pixels. OpenCV's SIFT doubles its input for the first octave, so on a finely sampled
  // panorama (the paper's 3000 x 750: 0.12° a cell) half size finds the blobs a sampling half as
  // fine has, at a quarter of the pixels. A Velodyne's ring image (0.09° columns, 0.4° rows) or a
  // cloud merged from several stations keeps its full size. 0: always full size.
  // Measured on the 18 regression projects at 3000 x 750: features 6.0-6.4 -> 4.6-5.3 s on the
  // 8-station street; 81 of 120 scans registered instead of 75, none wrong either way.
  double half_size_max_step_deg = 0.18;

  Status Validate() const;
};

struct ScanFeatures {
  std::vector<Keypoint> keypoints;
  std::vector<float> descriptors;  // keypoints.size() x 128, row-major
  int rows = 0;                    // panorama size the keypoints refer to
  int cols = 0;

  int size() const { return static_cast<int>(keypoints.size()); }
  const float* Descriptor(int i) const { return descriptors.data() + static_cast<std::size_t>(i) * kSiftDescriptorSize; }
};

// Runs SIFT on ReflectancePanorama(scan). Keypoints whose cell (nearest pixel) is empty or within
// mask_erosion_px of an empty cell are dropped. When wrap_margin_px > 0 and the scan covers 360°
// in azimuth (assumed for panoramic scans with an angular grid spanning > 350°), the image is
// padded left and right with columns from the other side, so blobs across the seam are found;
// each keypoint is kept once (the copy whose centre lies in the original columns). A panorama
// larger than options.strip_pixels is detected strip by strip (SiftStrips). Keypoints are sorted by decreasing response
// (ties: by v, then u), so the result is deterministic. Thread-safe (no shared state).
Expected<ScanFeatures> DetectFeatures(const Scan& scan, const SiftOptions& options = {});
// 2 when DetectFeatures works on a half-size image of the scan's panorama (half_size_max_step_deg), else 1.
int SiftImageScale(const Scan& scan, const SiftOptions& options);
// The strips DetectFeatures cuts the scan's panorama into (1: whole), and the most pixels one
// strip's detection works on (of the half-size image, when SiftImageScale is 2).
int SiftStrips(const Scan& scan, const SiftOptions& options);
std::size_t SiftStripPixels(const Scan& scan, const SiftOptions& options);

}  // namespace scanreg
