#include "ui/pair_panel.h"

#include <QComboBox>
#include <QFormLayout>
#include <QGroupBox>
#include <QScrollArea>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>
#include <cmath>

namespace scanreg::ui {
namespace {

QString Mm(double m) { return QString("%1 mm").arg(1000 * m, 0, 'f', 1); }
QString Percent(double f) { return QString("%1 %").arg(100 * f, 0, 'f', 1); }
QString ErrorText(const PoseError& e) {
  return QString("%1 mm, %2°").arg(1000 * e.position_m, 0, 'f', 1).arg(e.angle_rad * 180 / M_PI, 0, 'f', 4);
}

}  // namespace

PairPanel::PairPanel(QWidget* parent) : QWidget(parent) {
  setObjectName("PairPanel");
  setMinimumWidth(340);  // evidence values on one line
  parent_ = new QComboBox(this);
  parent_->setObjectName("PairParent");
  child_ = new QComboBox(this);
  child_->setObjectName("PairChild");
  coarse_ = new QComboBox(this);
  coarse_->setObjectName("PairCoarseMethod");
  for (CoarseMethod m : pipeline::AllCoarseMethods())
    coarse_->addItem(pipeline::CoarseMethodName(m), static_cast<int>(m));
  fine_ = new QComboBox(this);
  fine_->setObjectName("PairFineMethod");
  for (pipeline::FineMethod m : pipeline::AllFineMethods())
    fine_->addItem(pipeline::FineMethodName(m), static_cast<int>(m));

  auto* choose = new QFormLayout;
  choose->addRow(tr("Parent (fixed)"), parent_);
  choose->addRow(tr("Child (moved)"), child_);
  choose->addRow(tr("Coarse method"), coarse_);
  choose->addRow(tr("Fine method"), fine_);

  run_ = new QPushButton(tr("Register pair"), this);
  run_->setObjectName("PairRun");
  cancel_ = new QPushButton(tr("Cancel"), this);
  cancel_->setObjectName("PairCancel");
  use_ = new QPushButton(tr("Use this result"), this);
  use_->setObjectName("PairUse");
  use_->setToolTip(tr("Make this the child's link and move it (and the scans registered through it); undoable"));
  refine_ = new QPushButton(tr("Refine from current poses"), this);
  refine_->setObjectName("PairRefine");
  refine_->setToolTip(tr("Refine the child against the parent from where both stand now, with the fine step only "
                         "(no features); the result becomes the child's link (undoable)"));
  connect(refine_, &QPushButton::clicked, this, &PairPanel::RefineRequested);
  show_project_ = new QPushButton(tr("Show project"), this);
  show_project_->setToolTip(tr("Show all registered scans in the 3D view again"));
  connect(run_, &QPushButton::clicked, this, &PairPanel::RunRequested);
  connect(cancel_, &QPushButton::clicked, this, &PairPanel::CancelRequested);
  connect(use_, &QPushButton::clicked, this, &PairPanel::UseResultRequested);
  connect(show_project_, &QPushButton::clicked, this, &PairPanel::ShowProjectRequested);
  auto* buttons = new QHBoxLayout;
  buttons->addWidget(run_);
  buttons->addWidget(cancel_);
  auto* buttons2 = new QHBoxLayout;
  buttons2->addWidget(use_);
  buttons2->addWidget(show_project_);
  auto* buttons3 = new QHBoxLayout;
  buttons3->addWidget(refine_);

  auto* evidence = new QGroupBox(tr("Evidence"), this);
  auto* form = new QFormLayout(evidence);
  const std::pair<const char*, QString> rows[] = {{"status", tr("Status")},
                                                  {"reason", tr("Reason")},
                                                  {"method", tr("Method")},
                                                  {"matches", tr("Feature matches")},
                                                  {"reliable", tr("Reliable 3D pairs")},
                                                  {"inliers", tr("Coarse inliers")},
                                                  {"consistent", tr("Consistent")},
                                                  {"rms", tr("RMS (overlap)")},
                                                  {"overlap", tr("Overlap")},
                                                  {"conflict", tr("Free-space conflict")},
                                                  {"moving", tr("Moving objects")},
                                                  {"iterations", tr("Iterations")},
                                                  {"time", tr("Time")},
                                                  {"error", tr("Error vs reference")},
                                                  {"coarse_error", tr("Coarse error vs reference")}};
  for (const auto& [key, label] : rows) {
    auto* value = new QLabel("-", evidence);
    value->setObjectName(QString("Evidence_") + key);
    value->setTextInteractionFlags(Qt::TextSelectableByMouse);
    value->setWordWrap(true);
    form->addRow(label, value);
    fields_[key] = value;
  }

  auto* layout = new QVBoxLayout(this);
  layout->addLayout(choose);
  layout->addLayout(buttons);
  layout->addLayout(buttons2);
  layout->addLayout(buttons3);
  // The evidence scrolls when the window is short (a 1366 x 768 screen); the controls above do not.
  auto* scroll = new QScrollArea(this);
  scroll->setObjectName("EvidenceScroll");
  scroll->setWidget(evidence);
  scroll->setWidgetResizable(true);
  scroll->setFrameShape(QFrame::NoFrame);
  scroll->setHorizontalScrollBarPolicy(Qt::ScrollBarAlwaysOff);
  layout->addWidget(scroll, 1);
  SetRunning(false);
  use_->setEnabled(false);
}

void PairPanel::SetScans(const QStringList& names) {
  const QString p = parentScan(), c = childScan();
  for (QComboBox* box : {parent_, child_}) {
    box->clear();
    box->addItems(names);
  }
  if (names.contains(p) && names.contains(c)) {
    SetPair(p, c);
  } else if (names.size() >= 2) {
    child_->setCurrentIndex(1);
  }
}

void PairPanel::SetPair(const QString& parent, const QString& child) {
  parent_->setCurrentText(parent);
  child_->setCurrentText(child);
}

void PairPanel::SetMethods(CoarseMethod coarse, pipeline::FineMethod fine) {
  coarse_->setCurrentIndex(coarse_->findData(static_cast<int>(coarse)));
  fine_->setCurrentIndex(fine_->findData(static_cast<int>(fine)));
}

QString PairPanel::parentScan() const { return parent_->currentText(); }
QString PairPanel::childScan() const { return child_->currentText(); }
CoarseMethod PairPanel::coarseMethod() const { return static_cast<CoarseMethod>(coarse_->currentData().toInt()); }
pipeline::FineMethod PairPanel::fineMethod() const {
  return static_cast<pipeline::FineMethod>(fine_->currentData().toInt());
}

void PairPanel::SetRunning(bool running) {
  run_->setEnabled(!running);
  cancel_->setEnabled(running);
  if (running) use_->setEnabled(false);
  for (QComboBox* box : {parent_, child_, coarse_, fine_}) box->setEnabled(!running);
}

void PairPanel::SetField(const QString& field, const QString& text) {
  if (QLabel* label = fields_.value(field)) label->setText(text);
}

QString PairPanel::Evidence(const QString& field) const {
  const QLabel* label = fields_.value(field);
  return label ? label->text() : QString();
}

void PairPanel::ShowMessage(const QString& status, const QString& reason) {
  for (QLabel* label : fields_) label->setText("-");
  SetField("status", status);
  SetField("reason", reason);
  use_->setEnabled(false);
}

void PairPanel::ShowLinkFields(const io::LinkRecord& l) {
  const QColor colour = l.status == io::LinkStatus::kOk     ? QColor(20, 140, 60)
                        : l.status == io::LinkStatus::kWeak ? QColor(200, 120, 0)
                                                            : QColor(190, 40, 30);
  SetField("status", QString("<b style='color:%1'>%2</b>").arg(colour.name(), io::LinkStatusName(l.status)));
  SetField("reason", l.reason.empty() ? tr("all checks passed") : QString::fromStdString(l.reason));
  SetField("method", QString::fromStdString(l.method));
  SetField("matches", QString::number(l.matches));
  SetField("reliable", QString::number(l.reliable));
  SetField("inliers", QString::number(l.ransac_inliers));
  SetField("consistent", QString::number(l.consistent));
  // A pair that failed before its surfaces were compared measured no RMS or overlap: "—", not 0.
  const bool measured = l.status != io::LinkStatus::kFailed || l.rms_m > 0.0 || l.overlap > 0.0;
  const QString none = QStringLiteral("—");
  SetField("rms", measured ? Mm(l.rms_m) : none);
  SetField("overlap", measured ? Percent(l.overlap) : none);
  SetField("conflict", measured ? Percent(l.conflict) : none);
  SetField("moving", measured ? Percent(l.moving) : none);
  SetField("iterations", measured ? QString::number(l.iterations) : none);
  SetField("time", QString("%1 s").arg(l.seconds, 0, 'f', 2));
}

void PairPanel::ShowResult(const pipeline::PairInspection& result) {
  const io::LinkRecord& l = result.result.link;
  ShowLinkFields(l);
  SetField("error", result.reference_error ? ErrorText(*result.reference_error) : tr("no reference poses"));
  SetField("coarse_error",
           result.coarse_reference_error ? ErrorText(*result.coarse_reference_error) : tr("no reference poses"));
  use_->setEnabled(l.status != io::LinkStatus::kFailed);
}

void PairPanel::ShowStoredLink(const io::LinkRecord& link, const QString& note) {
  ShowLinkFields(link);
  SetField("error", note);
  SetField("coarse_error", QStringLiteral("—"));
  use_->setEnabled(false);  // already the project's
}

}  // namespace scanreg::ui
