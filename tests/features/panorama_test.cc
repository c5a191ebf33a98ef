#include "core/features/panorama.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/simulate/scanner.h"

namespace scanreg {
namespace {

TEST(PanoramaTest, MapsValidCellsToOneTo255AndEmptyToZero) {
  Scan scan("tiny", 3, 4);
  // Row 0 (top) holds the lowest and highest reflectances; one cell stays empty.
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      if (!(r == 2 && c == 3)) scan.Set(r, c, Eigen::Vector3f(1, 0, 0), 0.3f + 0.01f * (r * 4 + c));
  scan.Set(0, 0, Eigen::Vector3f(1, 0, 0), 0.0f);
  scan.Set(0, 1, Eigen::Vector3f(1, 0, 0), 1.0f);
  PanoramaOptions o;
  o.low_percentile = 0;
  o.high_percentile = 100;
  const cv::Mat image = ReflectancePanorama(scan, o);
  ASSERT_EQ(image.type(), CV_8UC1);
  ASSERT_EQ(image.rows, 3);
  ASSERT_EQ(image.cols, 4);
  EXPECT_EQ(image.at<std::uint8_t>(2, 3), 0);
  EXPECT_EQ(image.at<std::uint8_t>(0, 0), 1);
  EXPECT_EQ(image.at<std::uint8_t>(0, 1), 255);
  EXPECT_NEAR(image.at<std::uint8_t>(1, 0), 1 + 0.34 * 254, 1.0);  // reflectance 0.34, linear
  EXPECT_LT(image.at<std::uint8_t>(1, 0), image.at<std::uint8_t>(2, 0));
}

TEST(PanoramaTest, PercentileStretchIgnoresOutliers) {
  Scan scan("stretch", 10, 100);
  for (int r = 0; r < 10; ++r)
    for (int c = 0; c < 100; ++c) scan.Set(r, c, Eigen::Vector3f(1, 0, 0), 0.40f + 0.0002f * (r * 100 + c));
  scan.Set(5, 5, Eigen::Vector3f(1, 0, 0), 1.0f);  // one bright outlier
  const cv::Mat image = ReflectancePanorama(scan);
  EXPECT_EQ(image.at<std::uint8_t>(5, 5), 255);
  EXPECT_EQ(image.at<std::uint8_t>(0, 0), 1);
  // The bulk spans nearly the whole grey range despite the outlier.
  EXPECT_GT(image.at<std::uint8_t>(9, 98), 250);
  EXPECT_NEAR(image.at<std::uint8_t>(5, 0), 128, 6);
  EXPECT_TRUE(ReflectancePanorama(Scan("empty", 2, 2)).empty() == false);
  EXPECT_EQ(cv::countNonZero(ReflectancePanorama(Scan("empty", 2, 2))), 0);
}

// SPEC §2 step 1: SIFT on a full-size (3000 x 750) street panorama finds plenty of keypoints.
TEST(PanoramaTest, StreetPanoramaGivesAtLeast1000SiftKeypoints) {
  const Scene scene = MakeScene(SceneOptions());
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(2.0, 0.6, 1.7);
  pose.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  NullProgress progress;
  CancelToken cancel;
  const auto scan = SimulateScan(scene, pose, ScannerOptions(), "s01", progress, cancel);
  ASSERT_TRUE(scan.ok());
  const cv::Mat image = ReflectancePanorama(*scan);
  ASSERT_EQ(image.rows, 750);
  ASSERT_EQ(image.cols, 3000);
  if (const char* out = std::getenv("SCANREG_PANORAMA_OUT")) cv::imwrite(out, image);
  std::vector<cv::KeyPoint> keypoints;
  cv::SIFT::create()->detect(image, keypoints);
  std::printf("SIFT keypoints on a 3000 x 750 street panorama: %zu (valid cells %.1f %%)\n", keypoints.size(),
              100.0 * scan->CountValid() / scan->size());
  EXPECT_GE(keypoints.size(), 1000u);
}

}  // namespace
}  // namespace scanreg
