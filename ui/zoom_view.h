// A QGraphicsView for images and diagrams: the wheel zooms about the cursor, a drag pans, a
// double-click fits the scene, and a click that does not drag is reported in scene coordinates
// (picking). The panorama view, the point picker and the scan network use it.
#pragma once

#include <QGraphicsView>
#include <QPoint>
#include <functional>

namespace scanreg::ui {

class ZoomView : public QGraphicsView {
 public:
  explicit ZoomView(QWidget* parent);

  void Fit();  // the whole scene in view, aspect kept, margin_px around it
  // Room around the items on Fit, for items drawn at screen size (the network's nodes and labels).
  void SetMargin(int pixels) { margin_px_ = pixels; }
  // Called with the scene position of a click (press and release within a few pixels).
  std::function<void(QPointF scene_pos)> on_click;

 protected:
  void wheelEvent(QWheelEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void mouseDoubleClickEvent(QMouseEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;

 private:
  QPoint pressed_at_;
  int margin_px_ = 4;
};

}  // namespace scanreg::ui
