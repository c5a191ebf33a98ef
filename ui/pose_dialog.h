// Registration → Edit scan pose…: a scan's position (m) and heading / pitch / roll (degrees,
// R = Rz(heading)·Ry(pitch)·Rx(roll), core/geometry/pose_angles.h), and whether the scans
// registered through it move along. The edit itself is MainWindow::SetScanPose (undoable).
#pragma once

#include <QDialog>
#include <array>

#include <Eigen/Geometry>

class QCheckBox;
class QDoubleSpinBox;

namespace scanreg::ui {

class PoseDialog : public QDialog {
  Q_OBJECT
 public:
  PoseDialog(const QString& scan, const Eigen::Isometry3d& world_from_scan, QWidget* parent = nullptr);

  Eigen::Isometry3d Pose() const;
  bool MoveDependents() const;
  // x, y, z, heading, pitch, roll (for tests and keyboard users).
  QDoubleSpinBox* field(int i) const { return fields_[i]; }
  QCheckBox* moveDependentsBox() const { return move_dependents_; }

 private:
  std::array<QDoubleSpinBox*, 6> fields_{};
  QCheckBox* move_dependents_ = nullptr;
};

}  // namespace scanreg::ui
