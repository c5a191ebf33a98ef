// The scan network: scans as nodes (top view at their registered positions, on a circle while
// unregistered), links as edges coloured by status (ok green, weak orange, failed red dashed,
// loop checks grey dashed). The wheel zooms, a drag pans, a double-click on empty space fits;
// labels and nodes keep their screen size at any zoom. Links are picked within a few pixels; where
// several run close together the context menu lists each. Tooltips give a link's evidence and a
// scan's state. Targets seen by the scans (issue 15) are diamonds, blue and named when tied to a
// control point, red when a residual exceeds 1 cm. Right-click a scan to register it to another (its current parent and the match
// counts shown) or clear its parent; right-click a link to accept or reject it.
#pragma once

#include <QString>
#include <optional>
#include <string>
#include <vector>

#include "core/io/project.h"
#include "ui/zoom_view.h"

class QMenu;

namespace scanreg::ui {

class NetworkPanel : public ZoomView {
  Q_OBJECT

 public:
  explicit NetworkPanel(QWidget* parent = nullptr);
  void Show(const io::Project& project);
  int NodeCount() const { return nodes_; }
  int EdgeCount() const { return edges_; }
  int TargetCount() const { return targets_; }  // target marks drawn (one per target)

  // What is under a point of the view: the scan whose node is within a few pixels (empty: none), and
  // the links passing within tolerance_px, nearest first (indices into the project's links).
  QString ScanAt(QPoint view_pos) const;
  std::vector<int> LinksNear(QPoint view_pos, double tolerance_px = 6.0) const;
  const io::Project& project() const { return project_; }
  QString LinkToolTip(int link) const;
  QString ScanToolTip(const QString& scan) const;

 signals:
  // parent empty: clear the override.
  void ParentOverrideRequested(const QString& child, const QString& parent);
  void LinkDecisionRequested(const QString& parent, const QString& child, bool accept, bool reject);

 protected:
  void contextMenuEvent(QContextMenuEvent* event) override;
  bool viewportEvent(QEvent* event) override;

 private:
  void AddLinkActions(QMenu* menu, int link);
  io::Project project_;
  std::vector<QPointF> pos_;  // node positions, scene units
  double node_radius_ = 9.0;  // screen pixels (smaller on large projects)
  int nodes_ = 0;
  int edges_ = 0;
  int targets_ = 0;
};

}  // namespace scanreg::ui
