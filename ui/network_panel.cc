#include "ui/network_panel.h"

#include <QContextMenuEvent>
#include <QGraphicsEllipseItem>
#include <QGraphicsLineItem>
#include <QGraphicsSimpleTextItem>
#include <QMenu>
#include <cmath>

#include "ui/scan_cloud_actors.h"

namespace scanreg::ui {
namespace {

constexpr double kNodeRadius = 14.0;
const char* kScanKey = "scan";
const char* kParentKey = "parent";

// Node positions in scene units: registered scans at their x/y (y up on screen), others on a circle.
std::vector<QPointF> Layout(const io::Project& project) {
  const int n = static_cast<int>(project.scans.size());
  std::vector<QPointF> pos(n);
  double min_x = 1e300, max_x = -1e300, min_y = 1e300, max_y = -1e300;
  int registered = 0;
  for (const io::ProjectScan& s : project.scans) {
    if (!s.registered) continue;
    ++registered;
    const Eigen::Vector3d t = s.world_from_scan.translation();
    min_x = std::min(min_x, t.x()), max_x = std::max(max_x, t.x());
    min_y = std::min(min_y, t.y()), max_y = std::max(max_y, t.y());
  }
  const double extent = std::max({max_x - min_x, max_y - min_y, 1e-6});
  const double scale = registered >= 2 ? 600.0 / extent : 1.0;
  int k = 0;
  for (int i = 0; i < n; ++i) {
    const io::ProjectScan& s = project.scans[i];
    if (s.registered && registered >= 2) {
      const Eigen::Vector3d t = s.world_from_scan.translation();
      pos[i] = QPointF((t.x() - min_x) * scale, -(t.y() - min_y) * scale);
    } else {
      const double a = 2 * M_PI * k++ / std::max(1, n);
      pos[i] = QPointF(700 + 150 * std::cos(a), 150 * std::sin(a));
    }
  }
  return pos;
}

}  // namespace

NetworkPanel::NetworkPanel(QWidget* parent) : QGraphicsView(parent) {
  setObjectName("ScanNetwork");
  setScene(new QGraphicsScene(this));
  setRenderHint(QPainter::Antialiasing);
  setMinimumSize(240, 200);
  // The view fits the network on resize; scroll bars appearing and vanishing would re-fit it forever.
  setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  setVerticalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
}

void NetworkPanel::Show(const io::Project& project) {
  project_ = project;
  QGraphicsScene* s = scene();
  s->clear();
  nodes_ = edges_ = 0;
  const std::vector<QPointF> pos = Layout(project);
  for (const io::LinkRecord& l : project.links) {
    const int a = project.FindScan(l.parent), b = project.FindScan(l.child);
    if (a < 0 || b < 0) continue;
    QPen pen(Qt::gray, 2, Qt::DashLine);
    if (!l.loop_check) {
      if (l.status == io::LinkStatus::kOk) pen = QPen(QColor(40, 170, 70), 4);
      if (l.status == io::LinkStatus::kWeak) pen = QPen(QColor(240, 150, 30), 4);
      if (l.status == io::LinkStatus::kFailed) pen = QPen(QColor(200, 50, 40), 1.5, Qt::DashLine);
    }
    if (l.user_rejected) pen = QPen(QColor(120, 0, 0), 2, Qt::DotLine);
    auto* line = s->addLine(QLineF(pos[a], pos[b]), pen);
    line->setZValue(l.status == io::LinkStatus::kFailed ? -2 : -1);
    line->setData(0, kParentKey);
    line->setData(1, QString::fromStdString(l.parent));
    line->setData(2, QString::fromStdString(l.child));
    QString tip = QString("%1 → %2: %3 (%4 matches, %5 consistent, RMS %6 mm, overlap %7 %)")
                      .arg(QString::fromStdString(l.child), QString::fromStdString(l.parent),
                           io::LinkStatusName(l.status))
                      .arg(l.matches)
                      .arg(l.consistent)
                      .arg(l.rms_m * 1000, 0, 'f', 1)
                      .arg(l.overlap * 100, 0, 'f', 1);
    if (!l.reason.empty()) tip += "\n" + QString::fromStdString(l.reason);
    line->setToolTip(tip);
    ++edges_;
  }
  for (int i = 0; i < static_cast<int>(project.scans.size()); ++i) {
    const io::ProjectScan& scan = project.scans[i];
    double rgb[3];
    ScanColour(i, rgb);
    auto* node = s->addEllipse(pos[i].x() - kNodeRadius, pos[i].y() - kNodeRadius, 2 * kNodeRadius, 2 * kNodeRadius,
                               QPen(scan.registered ? Qt::black : QColor(200, 50, 40), scan.registered ? 1.5 : 3),
                               QBrush(QColor::fromRgbF(rgb[0], rgb[1], rgb[2])));
    node->setData(0, kScanKey);
    node->setData(1, QString::fromStdString(scan.name));
    QString tip = QString::fromStdString(scan.name) + (scan.registered ? "" : " (unregistered)");
    if (scan.parent_override) tip += "\nparent set by hand: " + QString::fromStdString(*scan.parent_override);
    node->setToolTip(tip);
    auto* label = s->addSimpleText(QString::fromStdString(scan.name) + (scan.parent_override ? " ✎" : ""));
    label->setPos(pos[i] + QPointF(kNodeRadius, -2 * kNodeRadius));
    ++nodes_;
  }
  fitInView(s->itemsBoundingRect().adjusted(-40, -40, 40, 40), Qt::KeepAspectRatio);
}

void NetworkPanel::resizeEvent(QResizeEvent* event) {
  QGraphicsView::resizeEvent(event);
  if (scene()) fitInView(scene()->itemsBoundingRect().adjusted(-40, -40, 40, 40), Qt::KeepAspectRatio);
}

void NetworkPanel::contextMenuEvent(QContextMenuEvent* event) {
  QGraphicsItem* item = itemAt(event->pos());
  if (!item) return;
  QMenu menu(this);
  if (item->data(0).toString() == kScanKey) {
    const QString child = item->data(1).toString();
    QMenu* parent_menu = menu.addMenu(tr("Register %1 to").arg(child));
    for (const io::ProjectScan& s : project_.scans) {
      const QString name = QString::fromStdString(s.name);
      if (name == child) continue;
      parent_menu->addAction(name, this, [this, child, name] { emit ParentOverrideRequested(child, name); });
    }
    const int index = project_.FindScan(child.toStdString());
    QAction* clear = menu.addAction(tr("Clear parent override"), this,
                                    [this, child] { emit ParentOverrideRequested(child, QString()); });
    clear->setEnabled(index >= 0 && project_.scans[index].parent_override.has_value());
  } else if (item->data(0).toString() == kParentKey) {
    const QString parent = item->data(1).toString(), child = item->data(2).toString();
    menu.addAction(tr("Accept link %1 → %2").arg(child, parent), this,
                   [this, parent, child] { emit LinkDecisionRequested(parent, child, true, false); });
    menu.addAction(tr("Reject link %1 → %2").arg(child, parent), this,
                   [this, parent, child] { emit LinkDecisionRequested(parent, child, false, true); });
    menu.addAction(tr("Clear decision"), this,
                   [this, parent, child] { emit LinkDecisionRequested(parent, child, false, false); });
  } else {
    return;
  }
  menu.exec(event->globalPos());
}

}  // namespace scanreg::ui
