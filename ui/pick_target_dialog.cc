#include "ui/pick_target_dialog.h"

#include <QComboBox>
#include <QDialogButtonBox>
#include <QFormLayout>
#include <QGraphicsEllipseItem>
#include <QGraphicsScene>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

#include "core/georef/picked_target.h"
#include "ui/picking_image.h"
#include "ui/zoom_view.h"

namespace scanreg::ui {
namespace {

constexpr int kSnapPixels = 8;

}  // namespace

PickTargetDialog::PickTargetDialog(const Scan& scan, const QStringList& names,
                                   const georef::SphereTargetOptions& spheres,
                                   const georef::CheckerTargetOptions& checkers, QWidget* parent)
    : QDialog(parent), scan_(scan), spheres_(spheres), checkers_(checkers) {
  setObjectName("PickTargetDialog");
  setWindowTitle(tr("Pick a target in %1").arg(QString::fromStdString(scan.name)));
  auto* help = new QLabel(tr("Click a target: a checkerboard's centre, a sphere, or a marked point. Boards and "
                             "spheres are fitted (checkerboard %1 mm, spheres of radius %2 mm: Registration → "
                             "Settings); anything else is taken as the clicked point. Wheel zooms, drag pans.")
                              .arg(checkers.size_m * 1000, 0, 'f', 0)
                              .arg(spheres.radius_m * 1000, 0, 'f', 1),
                          this);
  help->setWordWrap(true);
  scene_ = new QGraphicsScene(this);
  scene_->addPixmap(QPixmap::fromImage(PickingImage(scan_)))->setZValue(-1);
  view_ = new ZoomView(this);
  view_->setObjectName("PickTargetView");
  view_->setScene(scene_);
  view_->setMinimumSize(480, 160);
  view_->on_click = [this](QPointF p) { Pick(p); };
  name_ = new QComboBox(this);
  name_->setObjectName("PickTargetName");
  name_->setEditable(true);
  name_->addItems(names);
  name_->setCurrentText(QString());
  connect(name_, &QComboBox::currentTextChanged, this, [this] { Update(); });
  status_ = new QLabel(tr("Click a target in the panorama."), this);
  status_->setObjectName("PickTargetStatus");
  status_->setWordWrap(true);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Cancel, this);
  add_ = buttons->addButton(tr("Add target"), QDialogButtonBox::AcceptRole);
  add_->setObjectName("PickTargetAddButton");
  connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  auto* form = new QFormLayout;
  form->addRow(tr("Control point name:"), name_);
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(help);
  layout->addWidget(view_, 1);
  layout->addLayout(form);
  layout->addWidget(status_);
  layout->addWidget(buttons);
  resize(900, 480);
  view_->Fit();
  Update();
}

bool PickTargetDialog::Pick(QPointF pixel) {
  const auto cell = SnapToCell(scan_, pixel, kSnapPixels);
  if (!cell) {
    status_->setText(tr("No return near that pixel (sky or a gap): click on the target."));
    return false;
  }
  const georef::PickedTarget fit = georef::PickTargetAt(scan_, cell->first, cell->second, kSnapPixels, spheres_, checkers_);
  io::TargetRecord t;
  t.scan = scan_.name;
  t.kind = "picked";
  t.center = fit.center;
  t.sigma_m = fit.sigma_m;
  target_ = t;
  fit_ = QString::fromStdString(fit.fit);
  marker_ = QPointF(cell->second + 0.5, cell->first + 0.5);
  Update();
  return true;
}

void PickTargetDialog::SetName(const QString& name) { name_->setCurrentText(name); }

std::optional<io::TargetRecord> PickTargetDialog::Target() const {
  if (!target_) return std::nullopt;
  io::TargetRecord t = *target_;
  t.name = name_->currentText().trimmed().toStdString();
  return t;
}

QString PickTargetDialog::Status() const { return status_->text(); }

void PickTargetDialog::Update() {
  for (QGraphicsItem* item : scene_->items())
    if (item->zValue() >= 0) delete item;
  if (target_) {
    QPen pen(QColor(60, 220, 90), 2);
    pen.setCosmetic(true);
    auto* ring = scene_->addEllipse(-8, -8, 16, 16, pen);
    ring->setFlag(QGraphicsItem::ItemIgnoresTransformations);
    ring->setPos(marker_);
    ring->setZValue(1);
    const QString what = fit_ == "checker" ? tr("Checkerboard centre")
                         : fit_ == "sphere" ? tr("Sphere centre")
                                            : tr("The clicked point (no board or sphere fits there)");
    const Eigen::Vector3d& c = target_->center;
    status_->setText(tr("%1 at %2, %3, %4 m in the scan, σ %5 mm.")
                         .arg(what)
                         .arg(c.x(), 0, 'f', 3)
                         .arg(c.y(), 0, 'f', 3)
                         .arg(c.z(), 0, 'f', 3)
                         .arg(target_->sigma_m * 1000, 0, 'f', 1) +
                     (name_->currentText().trimmed().isEmpty()
                          ? tr(" Give it a control point's name to tie it to control (or leave it unnamed: "
                               "matched by the constellation).")
                          : QString()));
  }
  add_->setEnabled(target_.has_value() && !name_->currentText().contains(','));
}

}  // namespace scanreg::ui
