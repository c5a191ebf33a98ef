// The scan network: scans as nodes (top view at their registered positions, on a circle while
// unregistered), links as edges coloured by status (ok green, weak orange, failed red dashed,
// loop checks grey dashed) with their match counts. Right-click a scan to set or clear its
// parent; right-click a link to accept or reject it.
#pragma once

#include <QGraphicsView>
#include <optional>
#include <string>

#include "core/io/project.h"

namespace scanreg::ui {

class NetworkPanel : public QGraphicsView {
  Q_OBJECT

 public:
  explicit NetworkPanel(QWidget* parent = nullptr);
  void Show(const io::Project& project);
  int NodeCount() const { return nodes_; }
  int EdgeCount() const { return edges_; }

 signals:
  // parent empty: clear the override.
  void ParentOverrideRequested(const QString& child, const QString& parent);
  void LinkDecisionRequested(const QString& parent, const QString& child, bool accept, bool reject);

 protected:
  void contextMenuEvent(QContextMenuEvent* event) override;
  void resizeEvent(QResizeEvent* event) override;

 private:
  io::Project project_;
  int nodes_ = 0;
  int edges_ = 0;
};

}  // namespace scanreg::ui
