#include "ui/pick_points_dialog.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QFormLayout>
#include <QGraphicsEllipseItem>
#include <QGraphicsScene>
#include <QGraphicsSimpleTextItem>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QPushButton>
#include <QSplitter>
#include <QTableWidget>
#include <QVBoxLayout>
#include <algorithm>
#include <cmath>

#include "core/pipeline/manual_alignment.h"
#include "ui/picking_image.h"
#include "ui/zoom_view.h"

namespace scanreg::ui {
namespace {

constexpr int kSnapPixels = 8;

Eigen::Vector3d PointAt(const Scan& scan, int row, int col) { return scan.Point(row, col).cast<double>(); }

}  // namespace

PickPointsDialog::PickPointsDialog(FetchScan fetch, const QString& child, const QStringList& parents, QWidget* parent)
    : QDialog(parent), fetch_(std::move(fetch)), child_name_(child) {
  if (Expected<Scan> c = fetch_(child)) {
    child_scan_ = std::move(*c);
  } else {
    read_error_ = QString::fromStdString(c.error().message);
  }
  setObjectName("PickPointsDialog");
  setWindowTitle(tr("Align %1 by picked points").arg(child));
  parent_box_ = new QComboBox(this);
  parent_box_->setObjectName("PickParentBox");
  parent_box_->addItems(parents);
  connect(parent_box_, &QComboBox::currentTextChanged, this, [this] {
    parent_picks_.clear();
    child_picks_.clear();
    pick_order_parent_.clear();
    ShowScans();
  });
  auto* help = new QLabel(tr("Click the same point in both panoramas (a corner, a pole, a sign), at least 3 "
                             "pairs spread across the view — 2 when both scans are levelled. Wheel zooms, drag "
                             "pans, double-click fits."),
                          this);
  help->setWordWrap(true);
  parent_scene_ = new QGraphicsScene(this);
  child_scene_ = new QGraphicsScene(this);
  parent_view_ = new ZoomView(this);
  parent_view_->setObjectName("PickParentView");
  parent_view_->setScene(parent_scene_);
  parent_view_->on_click = [this](QPointF p) { Pick(true, p); };
  child_view_ = new ZoomView(this);
  child_view_->setObjectName("PickChildView");
  child_view_->setScene(child_scene_);
  child_view_->on_click = [this](QPointF p) { Pick(false, p); };
  for (ZoomView* v : {parent_view_, child_view_}) v->setMinimumSize(320, 90);
  table_ = new QTableWidget(0, 4, this);
  table_->setObjectName("PickTable");
  table_->setHorizontalHeaderLabels({tr("#"), tr("in parent (m)"), tr("in child (m)"), tr("residual")});
  table_->verticalHeader()->hide();
  table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  levelled_ = new QCheckBox(tr("Both scans are levelled (heading and position only; 2 pairs suffice)"), this);
  levelled_->setObjectName("PickLevelledBox");
  connect(levelled_, &QCheckBox::toggled, this, [this] { Update(); });
  status_ = new QLabel(this);
  status_->setObjectName("PickStatus");
  status_->setWordWrap(true);
  auto* undo = new QPushButton(tr("Remove last pick"), this);
  connect(undo, &QPushButton::clicked, this, &PickPointsDialog::RemoveLastPick);
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Cancel, this);
  align_ = buttons->addButton(tr("Align and refine"), QDialogButtonBox::AcceptRole);
  align_->setObjectName("PickAlignButton");
  connect(buttons, &QDialogButtonBox::accepted, this, &QDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);

  auto* views = new QSplitter(Qt::Vertical, this);
  auto* top = new QWidget(views);
  auto* top_layout = new QVBoxLayout(top);
  top_layout->setContentsMargins(0, 0, 0, 0);
  auto* parent_row = new QHBoxLayout;
  parent_row->addWidget(new QLabel(tr("Parent (registered):"), top));
  parent_row->addWidget(parent_box_, 1);
  top_layout->addLayout(parent_row);
  top_layout->addWidget(parent_view_, 1);
  auto* bottom = new QWidget(views);
  auto* bottom_layout = new QVBoxLayout(bottom);
  bottom_layout->setContentsMargins(0, 0, 0, 0);
  bottom_layout->addWidget(new QLabel(tr("Child: %1").arg(child), bottom));
  bottom_layout->addWidget(child_view_, 1);
  views->addWidget(top);
  views->addWidget(bottom);
  auto* side = new QVBoxLayout;
  side->addWidget(table_, 1);
  side->addWidget(levelled_);
  side->addWidget(status_);
  side->addWidget(undo);
  auto* body = new QHBoxLayout;
  body->addWidget(views, 3);
  body->addLayout(side, 2);
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(help);
  layout->addLayout(body, 1);
  layout->addWidget(buttons);
  resize(1100, 620);
  ShowScans();
}

QString PickPointsDialog::ParentScan() const { return parent_box_->currentText(); }

const Scan* PickPointsDialog::FindScan(const QString& name) const {
  if (child_scan_ && name == child_name_) return &*child_scan_;
  if (parent_scan_ && QString::fromStdString(parent_scan_->name) == name) return &*parent_scan_;
  return nullptr;
}

void PickPointsDialog::ShowScans() {
  parent_scan_.reset();
  if (Expected<Scan> p = fetch_(ParentScan())) {
    parent_scan_ = std::move(*p);
  } else {
    read_error_ = QString::fromStdString(p.error().message);
  }
  for (auto [scene, name] : {std::make_pair(parent_scene_, ParentScan()), std::make_pair(child_scene_, child_name_)}) {
    scene->clear();
    if (const Scan* s = FindScan(name)) scene->addPixmap(QPixmap::fromImage(PickingImage(*s)))->setZValue(-1);
  }
  parent_view_->Fit();
  child_view_->Fit();
  Update();
}

bool PickPointsDialog::Pick(bool in_parent, QPointF pixel) {
  const Scan* scan = FindScan(in_parent ? ParentScan() : child_name_);
  if (!scan) return false;
  const auto snapped = SnapToCell(*scan, pixel, kSnapPixels);
  if (!snapped) {
    status_->setText(tr("No return near that pixel (sky or a gap): pick a point on a surface."));
    return false;
  }
  const Cell cell{snapped->first, snapped->second};
  std::vector<Cell>& side = in_parent ? parent_picks_ : child_picks_;
  std::vector<Cell>& other = in_parent ? child_picks_ : parent_picks_;
  if (side.size() > other.size()) side.back() = cell;  // a second click on the same side moves the open pick
  else {
    side.push_back(cell);
    pick_order_parent_.push_back(in_parent);
  }
  Update();
  return true;
}

void PickPointsDialog::RemoveLastPick() {
  if (pick_order_parent_.empty()) return;
  (pick_order_parent_.back() ? parent_picks_ : child_picks_).pop_back();
  pick_order_parent_.pop_back();
  Update();
}

int PickPointsDialog::PairCount() const { return static_cast<int>(std::min(parent_picks_.size(), child_picks_.size())); }

bool PickPointsDialog::Levelled() const { return levelled_->isChecked(); }

std::vector<io::PickedPoint> PickPointsDialog::Pairs() const {
  std::vector<io::PickedPoint> out;
  const Scan* p = FindScan(ParentScan());
  const Scan* c = FindScan(child_name_);
  if (!p || !c) return out;
  for (int i = 0; i < PairCount(); ++i)
    out.push_back({PointAt(*p, parent_picks_[i].row, parent_picks_[i].col),
                   PointAt(*c, child_picks_[i].row, child_picks_[i].col)});
  return out;
}

QString PickPointsDialog::Status() const { return status_->text(); }

void PickPointsDialog::Update() {
  // Markers: numbered circles, green for complete pairs, orange for the open pick.
  for (QGraphicsScene* scene : {parent_scene_, child_scene_})
    for (QGraphicsItem* item : scene->items())
      if (item->zValue() >= 0) delete item;
  const int pairs = PairCount();
  auto mark = [&](QGraphicsScene* scene, const std::vector<Cell>& picks) {
    for (std::size_t i = 0; i < picks.size(); ++i) {
      const QColor colour = static_cast<int>(i) < pairs ? QColor(60, 220, 90) : QColor(255, 150, 30);
      QPen pen(colour, 2);
      pen.setCosmetic(true);
      auto* ring = scene->addEllipse(-7, -7, 14, 14, pen);
      ring->setFlag(QGraphicsItem::ItemIgnoresTransformations);
      ring->setPos(picks[i].col + 0.5, picks[i].row + 0.5);
      ring->setZValue(1);
      auto* label = scene->addSimpleText(QString::number(i + 1));
      label->setBrush(colour);
      label->setFlag(QGraphicsItem::ItemIgnoresTransformations);
      label->setPos(picks[i].col + 0.5, picks[i].row + 0.5);
      label->setZValue(1);
    }
  };
  mark(parent_scene_, parent_picks_);
  mark(child_scene_, child_picks_);

  const std::vector<io::PickedPoint> pts = Pairs();
  const int need = Levelled() ? 2 : 3;
  Expected<pipeline::PickedFit> fit = pipeline::FitPickedPoints(pts, Levelled());
  table_->setRowCount(pairs);
  auto xyz = [](const Eigen::Vector3d& v) { return QString("%1, %2, %3").arg(v.x(), 0, 'f', 2).arg(v.y(), 0, 'f', 2).arg(v.z(), 0, 'f', 2); };
  for (int i = 0; i < pairs; ++i) {
    table_->setItem(i, 0, new QTableWidgetItem(QString::number(i + 1)));
    table_->setItem(i, 1, new QTableWidgetItem(xyz(pts[i].parent)));
    table_->setItem(i, 2, new QTableWidgetItem(xyz(pts[i].child)));
    table_->setItem(i, 3, new QTableWidgetItem(fit ? tr("%1 mm").arg(1e3 * fit->residual_m[i], 0, 'f', 0) : "—"));
  }
  if (!read_error_.isEmpty() && (!parent_scan_ || !child_scan_)) {
    status_->setText(read_error_);
  } else if (pairs < need) {
    status_->setText(tr("%n more pair(s) to pick.", "", need - pairs));
  } else if (!fit) {
    status_->setText(QString::fromStdString(fit.error().message));
  } else {
    status_->setText(tr("%1 pairs: RMS %2 mm, largest %3 mm. The fine step refines from this pose.")
                         .arg(pairs)
                         .arg(1e3 * fit->rms_m, 0, 'f', 0)
                         .arg(1e3 * *std::max_element(fit->residual_m.begin(), fit->residual_m.end()), 0, 'f', 0));
  }
  align_->setEnabled(fit.ok() && pairs >= need);
}

}  // namespace scanreg::ui
