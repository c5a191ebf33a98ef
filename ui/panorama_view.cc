#include "ui/panorama_view.h"

#include <QCheckBox>
#include <QGraphicsEllipseItem>
#include <QGraphicsLineItem>
#include <QGraphicsPixmapItem>
#include <QGraphicsScene>
#include <QGraphicsSimpleTextItem>
#include <QGraphicsView>
#include <QHBoxLayout>
#include <QLabel>
#include <QVBoxLayout>
#include <algorithm>

#include "ui/zoom_view.h"

namespace scanreg::ui {
namespace {

enum ItemKind { kKeypoint = 1, kInlier = 2, kOutlier = 3 };
constexpr double kPairGap = 40.0;  // pixels between the two panoramas of a pair

QImage ToImage(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1) return {};
  return QImage(gray.data, gray.cols, gray.rows, static_cast<int>(gray.step), QImage::Format_Grayscale8).copy();
}

}  // namespace

PanoramaView::PanoramaView(QWidget* parent) : QWidget(parent) {
  setObjectName("PanoramaView");
  caption_ = new QLabel(this);
  caption_->setObjectName("PanoramaCaption");
  caption_->setTextFormat(Qt::RichText);
  show_outliers_ = new QCheckBox(tr("Show outlier matches"), this);
  show_outliers_->setChecked(true);
  show_outliers_->hide();
  connect(show_outliers_, &QCheckBox::toggled, this, [this] { UpdateOutlierVisibility(); });
  scene_ = new QGraphicsScene(this);
  auto* view = new ZoomView(this);
  view->setScene(scene_);
  view_ = view;
  auto* top = new QHBoxLayout;
  top->addWidget(caption_, 1);
  top->addWidget(show_outliers_);
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(4, 4, 4, 4);
  layout->addLayout(top);
  layout->addWidget(view_, 1);
  ShowMessage(tr("Select a scan in the scan list, or a cell of the confusion matrix, to see its panorama."));
}

void PanoramaView::Reset() {
  scene_->clear();
  image_size_ = QSize();
  shown_scan_.clear();
  show_outliers_->hide();
}

void PanoramaView::ShowMessage(const QString& text) {
  Reset();
  caption_->setText(text);
}

void PanoramaView::AddImage(const cv::Mat& image, double y) {
  auto* item = scene_->addPixmap(QPixmap::fromImage(ToImage(image)));
  item->setPos(0, y);
  item->setTransformationMode(Qt::SmoothTransformation);
  item->setZValue(-1);
}

void PanoramaView::AddKeypoints(const std::vector<Keypoint>& keypoints, double y) {
  QPen pen(QColor(255, 210, 40), 0);  // cosmetic: one screen pixel at any zoom
  for (const Keypoint& k : keypoints) {
    const double r = std::clamp(0.5 * k.size, 2.0, 12.0);
    auto* item = scene_->addEllipse(k.u - r, y + k.v - r, 2 * r, 2 * r, pen);
    item->setData(0, kKeypoint);
  }
}

void PanoramaView::ShowScan(const PanoramaImage& scan) {
  Reset();
  AddImage(scan.image, 0);
  AddKeypoints(scan.keypoints, 0);
  image_size_ = QSize(scan.image.cols, scan.image.rows);
  shown_scan_ = scan.scan;
  caption_->setText(tr("<b>%1</b> — reflectance panorama %2 × %3 px, %4 SIFT keypoints")
                        .arg(scan.scan)
                        .arg(scan.image.cols)
                        .arg(scan.image.rows)
                        .arg(scan.keypoints.size()));
  static_cast<ZoomView*>(view_)->Fit();
}

void PanoramaView::ShowPair(const PanoramaImage& parent, const PanoramaImage& child,
                            const std::vector<FeatureMatch>& matches, const std::vector<std::uint8_t>& inlier) {
  Reset();
  const double y_child = parent.image.rows + kPairGap;
  AddImage(parent.image, 0);
  AddImage(child.image, y_child);
  const QColor label_colour(230, 230, 230);
  auto* a = scene_->addSimpleText(tr("%1 (parent)").arg(parent.scan));
  a->setBrush(label_colour);
  a->setPos(4, parent.image.rows + 4);
  auto* b = scene_->addSimpleText(tr("%1 (child)").arg(child.scan));
  b->setBrush(label_colour);
  b->setPos(4, y_child - 20);
  // Cosmetic pens: the same width on screen at any zoom.
  QPen inlier_pen(QColor(40, 230, 90), 2), outlier_pen(QColor(235, 60, 45, 110), 0);
  inlier_pen.setCosmetic(true);
  int inliers = 0;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    const FeatureMatch& m = matches[i];
    if (m.query < 0 || m.train < 0 || m.query >= static_cast<int>(parent.keypoints.size()) ||
        m.train >= static_cast<int>(child.keypoints.size())) {
      continue;
    }
    const Keypoint& p = parent.keypoints[m.query];
    const Keypoint& c = child.keypoints[m.train];
    const bool in = i < inlier.size() && inlier[i];
    inliers += in;
    auto* line = scene_->addLine(p.u, p.v, c.u, y_child + c.v, in ? inlier_pen : outlier_pen);
    line->setData(0, in ? kInlier : kOutlier);
    line->setZValue(in ? 2 : 1);
  }
  image_size_ = QSize(parent.image.cols, parent.image.rows);
  shown_scan_ = child.scan + " → " + parent.scan;
  show_outliers_->show();
  UpdateOutlierVisibility();
  caption_->setText(tr("<b>%1 → %2</b> — %3 matches: <span style='color:#1a9e3c'>%4 coarse inliers</span>, "
                       "<span style='color:#c8322a'>%5 outliers</span>")
                        .arg(child.scan, parent.scan)
                        .arg(matches.size())
                        .arg(inliers)
                        .arg(static_cast<int>(matches.size()) - inliers));
  static_cast<ZoomView*>(view_)->Fit();
}

void PanoramaView::UpdateOutlierVisibility() {
  for (QGraphicsItem* item : scene_->items())
    if (item->data(0).toInt() == kOutlier) item->setVisible(show_outliers_->isChecked());
}

int PanoramaView::CountItems(int kind) const {
  int n = 0;
  for (QGraphicsItem* item : scene_->items()) n += item->data(0).toInt() == kind;
  return n;
}

int PanoramaView::KeypointMarkerCount() const { return CountItems(kKeypoint); }
int PanoramaView::InlierLineCount() const { return CountItems(kInlier); }
int PanoramaView::OutlierLineCount() const { return CountItems(kOutlier); }
QString PanoramaView::Caption() const { return caption_->text(); }

}  // namespace scanreg::ui
