#include "ui/project_panels.h"

#include <QHeaderView>
#include <cmath>

#include "core/geometry/transform.h"

namespace scanreg::ui {
namespace {

QTableWidgetItem* Item(const QString& text, Qt::Alignment align = Qt::AlignRight | Qt::AlignVCenter) {
  auto* item = new QTableWidgetItem(text);
  item->setTextAlignment(align);
  item->setFlags(Qt::ItemIsSelectable | Qt::ItemIsEnabled);
  return item;
}

}  // namespace

ScanListPanel::ScanListPanel(QWidget* parent) : QTableWidget(parent) {
  setObjectName("ScanList");
  setColumnCount(8);
  setHorizontalHeaderLabels({tr("Scan"), tr("Size"), tr("Points"), tr("Status"), tr("X (m)"), tr("Y (m)"), tr("Z (m)"),
                             tr("Error vs reference")});
  verticalHeader()->hide();
  horizontalHeader()->setStretchLastSection(true);
  setSelectionBehavior(QAbstractItemView::SelectRows);
  connect(this, &QTableWidget::itemChanged, this, [this](QTableWidgetItem* item) {
    if (item->column() != 0 || !(item->flags() & Qt::ItemIsUserCheckable)) return;
    const bool visible = item->checkState() == Qt::Checked;
    if (visible == !hidden_.contains(item->text())) return;
    if (visible) {
      hidden_.remove(item->text());
    } else {
      hidden_.insert(item->text());
    }
    emit ScanVisibilityChanged(item->text(), visible);
  });
}

void ScanListPanel::Show(const io::Project& project, const std::vector<Scan>& scans) {
  const QSignalBlocker blocker(this);  // the check boxes are set, not changed by the user
  setRowCount(static_cast<int>(project.scans.size()));
  // Errors relative to the root, so that the datum of the registration does not matter.
  const int root = project.root ? project.FindScan(*project.root) : -1;
  for (int i = 0; i < rowCount(); ++i) {
    const io::ProjectScan& s = project.scans[i];
    const Scan* scan = i < static_cast<int>(scans.size()) ? &scans[i] : nullptr;
    QTableWidgetItem* name = Item(QString::fromStdString(s.name), Qt::AlignLeft | Qt::AlignVCenter);
    name->setFlags(name->flags() | Qt::ItemIsUserCheckable);
    name->setCheckState(hidden_.contains(name->text()) ? Qt::Unchecked : Qt::Checked);
    name->setToolTip(tr("Uncheck to hide the scan in the 3D view"));
    setItem(i, 0, name);
    setItem(i, 1, Item(scan ? QString("%1 × %2").arg(scan->cols).arg(scan->rows) : "-"));
    setItem(i, 2, Item(scan ? QString::number(scan->CountValid()) : "-"));
    const io::PoseState state = io::ScanPoseState(s);
    QTableWidgetItem* status = Item(tr(io::PoseStateName(state)), Qt::AlignCenter);
    status->setForeground(state == io::PoseState::kUnregistered ? QColor(190, 60, 40)
                          : state == io::PoseState::kManual     ? QColor(200, 130, 0)
                          : state == io::PoseState::kImported   ? QColor(40, 90, 170)
                                                                : QColor(20, 140, 60));
    if (state == io::PoseState::kManual) {
      status->setToolTip(tr("Placed by hand (Registration → Edit scan pose): no link evidence"));
    } else if (state == io::PoseState::kImported) {
      status->setToolTip(tr("Pose read from a file (pose file or the scan's header): no link evidence of ours"));
    }
    setItem(i, 3, status);
    const Eigen::Vector3d t = s.world_from_scan.translation();
    for (int k = 0; k < 3; ++k) setItem(i, 4 + k, Item(QString::number(t[k], 'f', 3)));
    QString error = "-";
    if (s.registered && root >= 0 && s.reference_world_from_scan && project.scans[root].reference_world_from_scan) {
      const Eigen::Isometry3d est = project.scans[root].world_from_scan.inverse() * s.world_from_scan;
      const Eigen::Isometry3d ref =
          project.scans[root].reference_world_from_scan->inverse() * *s.reference_world_from_scan;
      const PoseError e = ComparePoses(est, ref);
      error = QString("%1 mm, %2°").arg(e.position_m * 1000, 0, 'f', 1).arg(e.angle_rad * 180 / M_PI, 0, 'f', 4);
    }
    setItem(i, 7, Item(error, Qt::AlignLeft | Qt::AlignVCenter));
  }
  resizeColumnsToContents();
}

ConfusionPanel::ConfusionPanel(QWidget* parent) : QTableWidget(parent) { setObjectName("ConfusionMatrix"); }

void ConfusionPanel::Show(const Eigen::MatrixXi& confusion, const std::vector<std::string>& names) {
  const int n = static_cast<int>(confusion.rows());
  setRowCount(n);
  setColumnCount(n);
  QStringList labels;
  for (const std::string& name : names) labels << QString::fromStdString(name);
  setHorizontalHeaderLabels(labels);
  setVerticalHeaderLabels(labels);
  int max_off = 1;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (i != j) max_off = std::max(max_off, confusion(i, j));
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      QTableWidgetItem* item = Item(QString::number(confusion(i, j)), Qt::AlignCenter);
      if (i == j) {
        item->setBackground(QColor(210, 210, 210));
      } else {
        const double f = double(confusion(i, j)) / max_off;  // white -> deep blue
        item->setBackground(QColor::fromRgbF(1.0 - 0.8 * f, 1.0 - 0.6 * f, 1.0));
        if (f > 0.6) item->setForeground(Qt::white);
      }
      setItem(i, j, item);
    }
  }
  resizeColumnsToContents();
}

LogPanel::LogPanel(QWidget* parent) : QPlainTextEdit(parent) {
  setObjectName("Log");
  setReadOnly(true);
  setMaximumBlockCount(5000);
}

void LogPanel::Append(const QString& level, const QString& message) { appendPlainText(level + ": " + message); }

}  // namespace scanreg::ui
