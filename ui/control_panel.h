// The georeferencing dock (issue 15): one row per control point of the project with the last
// adjustment's residual (ΔE, ΔN, ΔH, 3D, left-out), its role (used, check, blunder, not found) and
// its grade against the tolerance (green / orange / red rows), and a line above saying whether the
// project is placed on its control, with the RMS.
#pragma once

#include <QLabel>
#include <QTableWidget>
#include <QWidget>

#include "core/io/project.h"

namespace scanreg::ui {

class ControlPanel : public QWidget {
  Q_OBJECT

 public:
  explicit ControlPanel(QWidget* parent = nullptr);
  void Show(const io::Project& project);

  QTableWidget* table() const { return table_; }
  QString summary() const { return summary_->text(); }

 private:
  QLabel* summary_;
  QTableWidget* table_;
};

}  // namespace scanreg::ui
