#include "ui/pose_dialog.h"

#include <QCheckBox>
#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QLabel>
#include <QVBoxLayout>
#include <cmath>

#include "core/geometry/pose_angles.h"

namespace scanreg::ui {
namespace {
constexpr double kDeg = 180.0 / M_PI;
}

PoseDialog::PoseDialog(const QString& scan, const Eigen::Isometry3d& world_from_scan, QWidget* parent)
    : QDialog(parent) {
  setWindowTitle(tr("Edit pose of %1").arg(scan));
  auto* layout = new QVBoxLayout(this);
  auto* intro = new QLabel(tr("Place <b>%1</b> by hand. Its pose will carry no link evidence and is "
                              "marked <i>manual</i> in the scan list and the report. Undo restores it.")
                               .arg(scan.toHtmlEscaped()));
  intro->setWordWrap(true);
  layout->addWidget(intro);
  auto* form = new QFormLayout;
  const HeadingPitchRoll a = HeadingPitchRollFromRotation(world_from_scan.linear());
  const Eigen::Vector3d t = world_from_scan.translation();
  const double values[6] = {t.x(), t.y(), t.z(), a.heading * kDeg, a.pitch * kDeg, a.roll * kDeg};
  const QString labels[6] = {tr("x (m)"), tr("y (m)"), tr("z (m)"), tr("heading (°)"), tr("pitch (°)"), tr("roll (°)")};
  for (int i = 0; i < 6; ++i) {
    auto* box = new QDoubleSpinBox(this);
    box->setDecimals(4);
    box->setRange(i < 3 ? -1e8 : (i == 4 ? -90.0 : -180.0), i < 3 ? 1e8 : (i == 4 ? 90.0 : 180.0));
    box->setSingleStep(i < 3 ? 0.01 : 0.1);
    box->setValue(values[i]);
    box->setObjectName(QStringLiteral("pose_field_%1").arg(i));
    form->addRow(labels[i], box);
    fields_[i] = box;
  }
  layout->addLayout(form);
  move_dependents_ = new QCheckBox(tr("Move the scans registered through it along"), this);
  move_dependents_->setChecked(true);
  layout->addWidget(move_dependents_);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel, this);
  connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  layout->addWidget(buttons);
}

Eigen::Isometry3d PoseDialog::Pose() const {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(fields_[0]->value(), fields_[1]->value(), fields_[2]->value());
  pose.linear() = RotationFromHeadingPitchRoll(
      {fields_[3]->value() / kDeg, fields_[4]->value() / kDeg, fields_[5]->value() / kDeg});
  return pose;
}

bool PoseDialog::MoveDependents() const { return move_dependents_->isChecked(); }

}  // namespace scanreg::ui
