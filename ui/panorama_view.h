// The panorama view: a scan's reflectance panorama with its SIFT keypoints (yellow circles), or a
// pair's two panoramas stacked (parent on top) with their feature matches drawn between them,
// coarse RANSAC inliers in green and outliers in red. Wheel zooms, drag pans, double-click fits.
#pragma once

#include <QString>
#include <QWidget>
#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "core/features/matching.h"
#include "core/features/sift.h"

class QCheckBox;
class QGraphicsScene;
class QGraphicsView;
class QLabel;

namespace scanreg::ui {

// A panorama and its keypoints, as the worker computed them (by value).
struct PanoramaImage {
  QString scan;
  cv::Mat image;  // CV_8UC1, rows x cols (core/features/panorama.h)
  std::vector<Keypoint> keypoints;
};

class PanoramaView : public QWidget {
  Q_OBJECT

 public:
  explicit PanoramaView(QWidget* parent = nullptr);

  void ShowMessage(const QString& text);  // nothing to show (and why)
  void ShowScan(const PanoramaImage& scan);
  // matches: query = parent keypoint, train = child keypoint; inlier: per match.
  void ShowPair(const PanoramaImage& parent, const PanoramaImage& child, const std::vector<FeatureMatch>& matches,
                const std::vector<std::uint8_t>& inlier);

  // What is drawn (for tests and the caption): counted from the scene's items.
  QSize ImageSize() const { return image_size_; }  // the (top) panorama in pixels; empty when none
  int KeypointMarkerCount() const;
  int InlierLineCount() const;
  int OutlierLineCount() const;
  QString Caption() const;
  QString ShownScan() const { return shown_scan_; }  // "child → parent" for a pair

 private:
  void Reset();
  void AddImage(const cv::Mat& image, double y);
  void AddKeypoints(const std::vector<Keypoint>& keypoints, double y);
  void UpdateOutlierVisibility();
  int CountItems(int kind) const;

  QLabel* caption_ = nullptr;
  QCheckBox* show_outliers_ = nullptr;
  QGraphicsView* view_ = nullptr;
  QGraphicsScene* scene_ = nullptr;
  QSize image_size_;
  QString shown_scan_;
};

}  // namespace scanreg::ui
