#include "ui/control_panel.h"

#include <QHeaderView>
#include <QVBoxLayout>

#include "core/pipeline/georeference_project.h"

namespace scanreg::ui {
namespace {

QTableWidgetItem* Cell(const QString& text, const QColor& background, bool left = false) {
  auto* item = new QTableWidgetItem(text);
  item->setTextAlignment((left ? Qt::AlignLeft : Qt::AlignRight) | Qt::AlignVCenter);
  item->setFlags(Qt::ItemIsSelectable | Qt::ItemIsEnabled);
  if (background.isValid()) item->setBackground(background);
  return item;
}

QColor GradeColour(const std::string& grade) {
  if (grade == "green") return QColor(214, 240, 214);
  if (grade == "orange") return QColor(255, 228, 181);
  if (grade == "red") return QColor(250, 200, 200);
  return QColor();
}

QString Mm(double metres) { return QString::number(metres * 1000, 'f', 1); }

}  // namespace

ControlPanel::ControlPanel(QWidget* parent) : QWidget(parent) {
  setObjectName("ControlPanel");
  summary_ = new QLabel(this);
  summary_->setObjectName("ControlSummary");
  summary_->setWordWrap(true);
  table_ = new QTableWidget(this);
  table_->setObjectName("ControlTable");
  table_->setColumnCount(9);
  table_->setHorizontalHeaderLabels({tr("Point"), tr("Role"), tr("Scans"), tr("ΔE (mm)"), tr("ΔN (mm)"), tr("ΔH (mm)"),
                                     tr("3D (mm)"), tr("Left out (mm)"), tr("Grade")});
  table_->verticalHeader()->hide();
  table_->horizontalHeader()->setStretchLastSection(true);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  layout->addWidget(summary_);
  layout->addWidget(table_);
}

void ControlPanel::Show(const io::Project& p) {
  table_->setRowCount(0);
  if (p.control.empty()) {
    summary_->setText(tr("No control points. File → Import control points… reads a CSV of name, E, N, H "
                         "[, sigma]; the next registration places the project on them through the sphere "
                         "targets in the scans."));
    return;
  }
  const io::GeorefRecord* g = p.georef ? &*p.georef : nullptr;
  if (!g) {
    summary_->setText(tr("%1 control points; the project is not placed on them yet (register to georeference "
                         "it; the log says why when it cannot).")
                          .arg(p.control.size()));
    table_->setRowCount(static_cast<int>(p.control.size()));
    for (int i = 0; i < table_->rowCount(); ++i) {
      const io::ControlPoint& c = p.control[i];
      table_->setItem(i, 0, Cell(QString::fromStdString(c.name), QColor(), true));
      table_->setItem(i, 1, Cell(c.check ? tr("check") : tr("—"), QColor(), true));
      for (int k = 2; k < 9; ++k) table_->setItem(i, k, Cell("-", QColor()));
    }
    return;
  }
  summary_->setText(tr("Georeferenced on %1 of %2 control points, %3 targets in the scans: RMS %4 mm "
                       "(tolerance %5 mm; green below half of it, orange up to it, red beyond).")
                        .arg(g->used)
                        .arg(p.control.size())
                        .arg(g->targets)
                        .arg(Mm(g->rms_m))
                        .arg(Mm(g->tolerance_m)));
  table_->setRowCount(static_cast<int>(g->control.size()));
  for (int i = 0; i < table_->rowCount(); ++i) {
    const io::ControlResidualRecord& r = g->control[i];
    const std::string grade = pipeline::ControlGrade(r, g->tolerance_m);
    const QColor colour = GradeColour(grade);
    const bool found = r.role != "not found";
    table_->setItem(i, 0, Cell(QString::fromStdString(r.name), colour, true));
    table_->setItem(i, 1, Cell(QString::fromStdString(r.role), colour, true));
    table_->setItem(i, 2, Cell(QString::number(r.observations), colour));
    table_->setItem(i, 3, Cell(found ? Mm(r.delta.x()) : "-", colour));
    table_->setItem(i, 4, Cell(found ? Mm(r.delta.y()) : "-", colour));
    table_->setItem(i, 5, Cell(found ? Mm(r.delta.z()) : "-", colour));
    table_->setItem(i, 6, Cell(found ? Mm(r.delta.norm()) : "-", colour));
    table_->setItem(i, 7, Cell(r.leave_one_out_m >= 0 ? Mm(r.leave_one_out_m) : "-", colour));
    table_->setItem(i, 8, Cell(QString::fromStdString(grade), colour, true));
    if (r.role == "blunder") {
      table_->item(i, 1)->setToolTip(tr("Left out: %1 mm from where the other control points place its target. "
                                        "Check its coordinates and name.")
                                         .arg(Mm(r.delta.norm())));
    }
  }
  table_->resizeColumnsToContents();
}

}  // namespace scanreg::ui
