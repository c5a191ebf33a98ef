#include "ui/zoom_view.h"

#include <QGraphicsScene>
#include <QMouseEvent>
#include <QWheelEvent>
#include <algorithm>

namespace scanreg::ui {

ZoomView::ZoomView(QWidget* parent) : QGraphicsView(parent) {
  setDragMode(QGraphicsView::ScrollHandDrag);  // panning works with the scroll bars hidden
  // Hidden scroll bars: fitting on resize cannot make them appear and disappear in a loop (the hang
  // seen in the network panel).
  setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  setVerticalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  setTransformationAnchor(QGraphicsView::AnchorUnderMouse);
  setRenderHint(QPainter::Antialiasing);
  setBackgroundBrush(QColor(28, 30, 34));
}

void ZoomView::Fit() {
  if (!scene() || scene()->items().isEmpty()) return;
  const QRectF items = scene()->itemsBoundingRect();
  // The scene's own rect only grows (a previous content would stay in it): pan over the items and as
  // much again around them.
  setSceneRect(items.adjusted(-items.width(), -items.height(), items.width(), items.height()));
  fitInView(items, Qt::KeepAspectRatio);
  const QSize v = viewport()->size();
  const double m = 2.0 * margin_px_;
  const double f = std::min(1.0 - m / std::max(2.0 * m, double(v.width())), 1.0 - m / std::max(2.0 * m, double(v.height())));
  scale(f, f);
  centerOn(items.center());
}

void ZoomView::wheelEvent(QWheelEvent* event) {
  const double factor = event->angleDelta().y() > 0 ? 1.25 : 0.8;
  scale(factor, factor);
}

void ZoomView::mousePressEvent(QMouseEvent* event) {
  pressed_at_ = event->pos();
  QGraphicsView::mousePressEvent(event);
}

void ZoomView::mouseReleaseEvent(QMouseEvent* event) {
  QGraphicsView::mouseReleaseEvent(event);
  if (event->button() == Qt::LeftButton && on_click && (event->pos() - pressed_at_).manhattanLength() <= 4)
    on_click(mapToScene(event->pos()));
}

void ZoomView::mouseDoubleClickEvent(QMouseEvent*) { Fit(); }

void ZoomView::resizeEvent(QResizeEvent* event) {
  QGraphicsView::resizeEvent(event);
  Fit();
}

}  // namespace scanreg::ui
