#include "ui/project_panels.h"

#include <QDateTime>
#include <QHeaderView>
#include <QTime>
#include <cmath>

#include "core/common/skipped_pair.h"
#include "core/geometry/transform.h"
#include "core/io/project_tree.h"

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
  setColumnCount(11);
  setHorizontalHeaderLabels({tr("Scan"), tr("Size"), tr("Points"), tr("Status"), tr("Parent"), tr("Link"),
                             tr("Reason"), tr("X (m)"), tr("Y (m)"), tr("Z (m)"), tr("Error vs reference")});
  setTextElideMode(Qt::ElideRight);  // long reasons: the tooltip holds the whole text
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

void ScanListPanel::Show(const io::Project& project, const std::vector<pipeline::ScanPreview>& scans) {
  const QSignalBlocker blocker(this);  // the check boxes are set, not changed by the user
  setRowCount(static_cast<int>(project.scans.size()));
  // Errors relative to the root, so that the datum of the registration does not matter.
  const int root = project.root ? project.FindScan(*project.root) : -1;
  const std::vector<bool> on_hand = io::RestsOnHandPlacement(project);
  for (int i = 0; i < rowCount(); ++i) {
    const io::ProjectScan& s = project.scans[i];
    const pipeline::ScanPreview* scan = i < static_cast<int>(scans.size()) ? &scans[i] : nullptr;
    QTableWidgetItem* name = Item(QString::fromStdString(s.name), Qt::AlignLeft | Qt::AlignVCenter);
    name->setFlags(name->flags() | Qt::ItemIsUserCheckable);
    name->setCheckState(hidden_.contains(name->text()) ? Qt::Unchecked : Qt::Checked);
    name->setToolTip(tr("Uncheck to hide the scan in the 3D view"));
    setItem(i, 0, name);
    setItem(i, 1, Item(scan ? QString("%1 × %2").arg(scan->full_cols).arg(scan->full_rows) : "-"));
    setItem(i, 2, Item(scan ? QString::number(scan->full_valid) : "-"));
    const io::PoseState state = io::ScanPoseState(s);
    QTableWidgetItem* status = Item(tr(io::PoseStateName(state)), Qt::AlignCenter);
    status->setForeground(state == io::PoseState::kUnregistered ? QColor(190, 60, 40)
                          : state == io::PoseState::kNotVerified ? QColor(215, 120, 0)
                          : state == io::PoseState::kManual     ? QColor(200, 130, 0)
                          : state == io::PoseState::kImported   ? QColor(40, 90, 170)
                                                                : QColor(20, 140, 60));
    if (state == io::PoseState::kManual) {
      status->setToolTip(tr("Placed by hand (Registration → Edit scan pose): no link evidence; Register all keeps "
                            "it (Registration → Release hand placement lets the registration place it)"));
    } else if (state == io::PoseState::kImported) {
      status->setToolTip(tr("Pose read from a file (pose file or the scan's header): no link evidence of ours"));
    } else if (state == io::PoseState::kNotVerified) {
      status->setToolTip(tr("Placed by the registration, but its pose is not verified: it stays at its start pose, "
                            "out of the merge and the export. Check the link in the scan network; accept it "
                            "(right-click) if the pose is right, and register again.\n%1")
                             .arg(QString::fromStdString(s.unregistered_reason)));
    } else if (state == io::PoseState::kUnregistered && !s.cluster.empty()) {
      status->setText(tr("cluster of %1").arg(QString::fromStdString(s.cluster)));
      status->setForeground(QColor(150, 80, 170));
      status->setToolTip(tr("Registered to the other scans of the cluster of %1 but not to the root: one link to a "
                            "registered scan (align by picked points, or a parent) places the whole cluster")
                             .arg(QString::fromStdString(s.cluster)));
    } else if (state == io::PoseState::kRegistered && on_hand[i]) {
      status->setText(tr("on a hand placement"));
      status->setForeground(QColor(200, 130, 0));
      status->setToolTip(tr("Registered through a scan placed by hand: its pose carries that placement's error"));
    }
    setItem(i, 3, status);
    // The link that placed the scan (its tree link), or the last attempt when none did.
    const io::LinkRecord* tree = nullptr;
    const io::LinkRecord* failed = nullptr;
    for (const io::LinkRecord& l : project.links) {
      if (l.child != s.name) continue;
      if (io::IsTreeLink(l)) tree = &l;
      if (l.status == io::LinkStatus::kFailed) failed = &l;
    }
    const io::LinkRecord* link = tree ? tree : failed;
    setItem(i, 4, Item(link ? QString::fromStdString(link->parent) : "—", Qt::AlignLeft | Qt::AlignVCenter));
    QString quality = "—", quality_tip;
    if (link) {
      quality = QString::fromStdString(io::LinkStatusName(link->status));
      if (link->status != io::LinkStatus::kFailed || link->rms_m > 0.0)  // a failed pair may never have been measured
        quality += QString(", %1 mm, %2 %").arg(link->rms_m * 1000, 0, 'f', 1).arg(link->overlap * 100, 0, 'f', 0);
      quality_tip = tr("%1 → %2 (%3): RMS %4 mm, overlap %5 %, %6 consistent correspondences")
                        .arg(QString::fromStdString(link->child), QString::fromStdString(link->parent),
                             QString::fromStdString(link->method))
                        .arg(link->rms_m * 1000, 0, 'f', 1)
                        .arg(link->overlap * 100, 0, 'f', 1)
                        .arg(link->consistent);
    }
    if (s.consistency_m) {  // refinement from current poses: checked against every overlap
      quality_tip += (quality_tip.isEmpty() ? "" : "\n") +
                     tr("overlaps agree to %1 mm (at the start pose %2 mm)")
                         .arg(*s.consistency_m * 1000, 0, 'f', 3)
                         .arg(s.start_consistency_m ? QString::number(*s.start_consistency_m * 1000, 'f', 3) : "—");
      if (s.conditioning) quality_tip += tr("; conditioning %1 (near 0: a direction of the pose is free)").arg(*s.conditioning, 0, 'f', 3);
    }
    QTableWidgetItem* quality_item = Item(quality, Qt::AlignLeft | Qt::AlignVCenter);
    quality_item->setToolTip(quality_tip);
    setItem(i, 5, quality_item);
    // A scan that kept its imported pose says why the registration could not place it.
    QString reason = QString::fromStdString(s.registered && !(s.imported_pose && !s.unregistered_reason.empty())
                                                ? (link && link == tree ? link->reason : std::string())
                                                : s.unregistered_reason);
    QTableWidgetItem* reason_item = Item(reason.isEmpty() ? "—" : reason, Qt::AlignLeft | Qt::AlignVCenter);
    reason_item->setToolTip(reason);  // the full text; the cell may be narrower
    setItem(i, 6, reason_item);
    const Eigen::Vector3d t = s.world_from_scan.translation();
    for (int k = 0; k < 3; ++k) setItem(i, 7 + k, Item(QString::number(t[k], 'f', 3)));
    QString error = "-";
    if (s.registered && root >= 0 && s.reference_world_from_scan && project.scans[root].reference_world_from_scan) {
      const Eigen::Isometry3d est = project.scans[root].world_from_scan.inverse() * s.world_from_scan;
      const Eigen::Isometry3d ref =
          project.scans[root].reference_world_from_scan->inverse() * *s.reference_world_from_scan;
      const PoseError e = ComparePoses(est, ref);
      error = QString("%1 mm, %2°").arg(e.position_m * 1000, 0, 'f', 1).arg(e.angle_rad * 180 / M_PI, 0, 'f', 4);
    }
    setItem(i, 10, Item(error, Qt::AlignLeft | Qt::AlignVCenter));
  }
  resizeColumnsToContents();
  for (int c : {5, 6})  // link figures and reasons can be long: the tooltip holds the whole text
    if (columnWidth(c) > 280) setColumnWidth(c, 280);
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
      const bool skipped = i != j && confusion(i, j) == kSkippedPair;
      QTableWidgetItem* item = Item(skipped ? QString("–") : QString::number(confusion(i, j)), Qt::AlignCenter);
      if (i == j) {
        item->setBackground(QColor(210, 210, 210));
      } else if (skipped) {
        item->setBackground(QColor(240, 240, 240));
        item->setForeground(QColor(150, 150, 150));
        item->setToolTip(tr("Not matched: not among the candidate pairs (setting register.candidates; 0 matches "
                            "every pair). Registering the pair by hand still matches it."));
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

void LogPanel::Append(const QString& level, const QString& message) {
  appendPlainText(QTime::currentTime().toString("HH:mm:ss") + "  " + level + ": " + message);
}

void LogPanel::Header(const QString& title) {
  appendPlainText(QString("── %1 — %2 ──").arg(title, QDateTime::currentDateTime().toString("yyyy-MM-dd HH:mm:ss")));
}

}  // namespace scanreg::ui
