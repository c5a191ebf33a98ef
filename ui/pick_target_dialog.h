// Georeferencing → Pick a target in scan… (issue 15, item 1): the scan's panorama; a click on a
// board, a sphere or a marked point picks it, refined by the same fits the automatic search uses
// (core/georef/picked_target.h), and the dialog says which fit placed it and how well. The target's
// name, from the project's control points or typed, ties it to control. Accepting hands the target
// to MainWindow::AddPickedTarget (an undoable edit).
#pragma once

#include <QDialog>
#include <QPointF>
#include <optional>

#include "core/geometry/scan.h"
#include "core/georef/checker_targets.h"
#include "core/georef/sphere_targets.h"
#include "core/io/project.h"

class QComboBox;
class QGraphicsScene;
class QLabel;
class QPushButton;

namespace scanreg::ui {

class ZoomView;

class PickTargetDialog : public QDialog {
  Q_OBJECT

 public:
  // scan: a copy is kept (the dialog does not block the window); names: the control points offered.
  PickTargetDialog(const Scan& scan, const QStringList& names, const georef::SphereTargetOptions& spheres,
                   const georef::CheckerTargetOptions& checkers, QWidget* parent = nullptr);

  // A click at `pixel` (column, row): snapped to the nearest cell with a return, then fitted.
  bool Pick(QPointF pixel);
  void SetName(const QString& name);
  // The picked target (kind "picked", in the scan's frame, named), when there is one.
  std::optional<io::TargetRecord> Target() const;
  QString Status() const;
  QPushButton* addButton() const { return add_; }

 private:
  void Update();

  Scan scan_;
  georef::SphereTargetOptions spheres_;
  georef::CheckerTargetOptions checkers_;
  std::optional<io::TargetRecord> target_;
  QPointF marker_;
  QString fit_;
  ZoomView* view_ = nullptr;
  QGraphicsScene* scene_ = nullptr;
  QComboBox* name_ = nullptr;
  QLabel* status_ = nullptr;
  QPushButton* add_ = nullptr;
};

}  // namespace scanreg::ui
