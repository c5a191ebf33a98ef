#include "core/features/sift.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>

#include "feature_fixtures.h"

namespace scanreg {
namespace {

TEST(SiftTest, ValidateRejectsNonsense) {
  EXPECT_TRUE(SiftOptions().Validate().ok());
  SiftOptions o;
  o.max_features = -1;
  EXPECT_FALSE(o.Validate().ok());
  o = SiftOptions();
  o.contrast_threshold = 0;
  EXPECT_FALSE(o.Validate().ok());
  o = SiftOptions();
  o.sigma = -1;
  EXPECT_FALSE(o.Validate().ok());
  o = SiftOptions();
  o.octave_layers = 0;
  EXPECT_FALSE(o.Validate().ok());
  o = SiftOptions();
  o.wrap_margin_px = -3;
  EXPECT_FALSE(o.Validate().ok());
  o = SiftOptions();
  o.strip_pixels = -1;
  EXPECT_FALSE(o.Validate().ok());
  Scan scan("s", 20, 20);
  EXPECT_EQ(DetectFeatures(scan, o).error().code, ErrorCode::kInvalidArgument);
}

TEST(SiftTest, EmptyScanGivesNoFeatures) {
  const auto f = DetectFeatures(Scan("empty", 50, 200));
  ASSERT_TRUE(f.ok());
  EXPECT_EQ(f->size(), 0);
  EXPECT_EQ(f->rows, 50);
  EXPECT_EQ(f->cols, 200);
}

// SPEC §2.1 at W's size: plenty of keypoints, none on (or next to) an empty cell.
TEST(SiftTest, FullSizeStationHasThousandsOfKeypointsNoneOnEmptyCells) {
  const Scan& scan = test::FullSizePair().at(0);
  ASSERT_EQ(scan.cols, 3000);
  const auto t0 = std::chrono::steady_clock::now();
  const auto f = DetectFeatures(scan);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_TRUE(f.ok()) << f.error().ToString();
  std::printf("SIFT on %dx%d: %d keypoints in %.2f s\n", scan.cols, scan.rows, f->size(), seconds);
  EXPECT_GE(f->size(), 1000);
  ASSERT_EQ(f->descriptors.size(), f->keypoints.size() * 128u);
  int near_seam = 0;
  for (const Keypoint& k : f->keypoints) {
    const int r = static_cast<int>(std::lround(k.v)), c = static_cast<int>(std::lround(k.u));
    ASSERT_TRUE(r >= 0 && r < scan.rows && c >= 0 && c < scan.cols) << k.u << " " << k.v;
    // Eroded mask: the cell and its neighbours within mask_erosion_px (2) are all valid.
    for (int dr = -2; dr <= 2; ++dr)
      for (int dc = -2; dc <= 2; ++dc) {
        const int rr = r + dr, cc = (c + dc + scan.cols) % scan.cols;
        if (rr < 0 || rr >= scan.rows) continue;
        ASSERT_TRUE(scan.IsValid(rr, cc)) << "keypoint at (" << k.u << ", " << k.v << ") next to an empty cell";
      }
    if (c < 5 || c >= scan.cols - 5) ++near_seam;
  }
  EXPECT_GT(near_seam, 0);  // the 360° wrap finds blobs across the seam
  for (int i = 1; i < f->size(); ++i) ASSERT_GE(f->keypoints[i - 1].response, f->keypoints[i].response);
}

// With the 360° wrap, turning the scanner by half a turn (a circular shift of the columns) shifts
// the keypoints and changes almost nothing else; without the wrap the seam loses keypoints.
TEST(SiftTest, WrapMakesKeypointsIndependentOfWhereTheSeamIs) {
  const Scan& scan = test::SmallProject().at(1);
  Scan shifted = scan;
  const int shift = (scan.cols / 2) / 64 * 64;  // keeps the octaves' sampling grids aligned
  for (int r = 0; r < scan.rows; ++r)
    for (int c = 0; c < scan.cols; ++c) {
      const int src = scan.Index(r, (c + shift) % scan.cols), dst = shifted.Index(r, c);
      shifted.points[dst] = scan.points[src];
      shifted.reflectance[dst] = scan.reflectance[src];
      shifted.valid[dst] = scan.valid[src];
    }
  for (int c = 0; c < scan.cols; ++c) shifted.angles.azimuth[c] = scan.angles.azimuth[(c + shift) % scan.cols];
  const auto a = DetectFeatures(scan);
  const auto b = DetectFeatures(shifted);
  ASSERT_TRUE(a.ok() && b.ok());
  // Every keypoint of b found again in a, shifted back, within 0.05 px.
  int found = 0;
  for (const Keypoint& kb : b->keypoints) {
    const float u = std::fmod(kb.u + shift, static_cast<float>(scan.cols));
    for (const Keypoint& ka : a->keypoints)
      if (std::abs(ka.v - kb.v) < 0.05f && std::abs(std::remainder(ka.u - u, static_cast<float>(scan.cols))) < 0.05f) {
        ++found;
        break;
      }
  }
  std::printf("keypoints %d / %d, %d found again after a half-turn\n", a->size(), b->size(), found);
  EXPECT_NEAR(a->size(), b->size(), 0.03 * a->size());
  EXPECT_GE(found, 0.95 * b->size());
}

TEST(SiftTest, MaxFeaturesKeepsTheStrongest) {
  const Scan& scan = test::SmallProject().at(0);
  const auto all = DetectFeatures(scan);
  SiftOptions o;
  o.max_features = 100;
  const auto best = DetectFeatures(scan, o);
  ASSERT_TRUE(all.ok() && best.ok());
  ASSERT_GT(all->size(), 100);
  ASSERT_EQ(best->size(), 100);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(best->keypoints[i].u, all->keypoints[i].u);
    EXPECT_EQ(best->keypoints[i].response, all->keypoints[i].response);
  }
}

// Issue 13: a panorama detected in column strips (SIFT's memory one strip's) finds the keypoints of
// the whole panorama — the same ones, with the same descriptors, except near a strip's border at
// coarse scales — and none twice across a border. Here W's 3000 x 750 in 4 strips.
TEST(SiftTest, StripsFindTheWholePanoramasKeypointsOnce) {
  const Scan& scan = test::FullSizePair().at(0);
  SiftOptions whole_options;  // at full size
  whole_options.strip_pixels = 0;
  whole_options.half_size_max_step_deg = 0;
  SiftOptions strip_options;
  strip_options.strip_pixels = scan.size() / 4;
  strip_options.half_size_max_step_deg = 0;
  ASSERT_EQ(SiftStrips(scan, whole_options), 1);
  ASSERT_EQ(SiftStrips(scan, strip_options), 4);
  EXPECT_LT(SiftStripPixels(scan, strip_options), scan.size() / 2);
  const auto whole = DetectFeatures(scan, whole_options);
  const auto strips = DetectFeatures(scan, strip_options);
  ASSERT_TRUE(whole.ok() && strips.ok());
  ASSERT_GT(whole->size(), 1000);
  // The same keypoint: within 0.01 px and with the same descriptor.
  auto same = [](const ScanFeatures& a, int i, const ScanFeatures& b, int j) {
    const Keypoint &ka = a.keypoints[i], &kb = b.keypoints[j];
    if (std::abs(ka.u - kb.u) > 0.01f || std::abs(ka.v - kb.v) > 0.01f || std::abs(ka.size - kb.size) > 0.01f)
      return false;
    float d = 0;
    for (int k = 0; k < kSiftDescriptorSize; ++k) d += std::abs(a.Descriptor(i)[k] - b.Descriptor(j)[k]);
    return d < 1e-3f * kSiftDescriptorSize;
  };
  auto found_in = [&](const ScanFeatures& a, const ScanFeatures& b) {
    int found = 0;
    for (int i = 0; i < a.size(); ++i)
      for (int j = 0; j < b.size(); ++j)
        if (same(a, i, b, j)) {
          ++found;
          break;
        }
    return found;
  };
  const int kept = found_in(*whole, *strips), extra = strips->size() - found_in(*strips, *whole);
  std::printf("whole %d keypoints, strips %d: %d of the whole's found, %d not in the whole\n", whole->size(),
              strips->size(), kept, extra);
  EXPECT_GE(kept, 0.99 * whole->size());
  EXPECT_LE(extra, 0.01 * whole->size());
  int twice = 0;  // the same keypoint from two strips
  for (int i = 0; i < strips->size(); ++i)
    for (int j = i + 1; j < strips->size(); ++j) twice += same(*strips, i, *strips, j);
  EXPECT_EQ(twice, 0);
  for (int i = 1; i < strips->size(); ++i) ASSERT_GE(strips->keypoints[i - 1].response, strips->keypoints[i].response);
}

}  // namespace
}  // namespace scanreg
