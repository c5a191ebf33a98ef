// Registration → Align by picked points… (issue 14, item 2): the parent's panorama above the
// child's; a click in each picks the same point in both scans (snapped to the nearest cell with a
// return). Each pair is listed with its residual against the pose of all pairs as soon as there
// are enough (3, or 2 for levelled scans), so a wrong pick shows before anything runs. Accepting
// hands the pairs to MainWindow::AlignFromPickedPoints (a job: fit, then the fine step).
#pragma once

#include <QDialog>
#include <QPointF>
#include <QString>
#include <QStringList>
#include <functional>
#include <optional>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"

class QCheckBox;
class QComboBox;
class QGraphicsScene;
class QLabel;
class QPushButton;
class QTableWidget;

namespace scanreg::ui {

class ZoomView;

class PickPointsDialog : public QDialog {
  Q_OBJECT

 public:
  // child: the scan to align; parents: the registered scans it may be aligned to (first: the
  // default). `fetch` reads a scan of the open project in full by name (an error: gone, or its file
  // cannot be read; the dialog says so); the dialog keeps the two scans it shows (it does not block
  // the window), never the whole project.
  using FetchScan = std::function<Expected<Scan>(const QString& name)>;
  PickPointsDialog(FetchScan fetch, const QString& child, const QStringList& parents, QWidget* parent = nullptr);

  QString ParentScan() const;
  QString ChildScan() const { return child_name_; }
  // A click at `pixel` (column, row) of one panorama: snapped to the nearest cell with a return
  // within 8 pixels; false (nothing picked) when there is none.
  bool Pick(bool in_parent, QPointF pixel);
  void RemoveLastPick();
  int PairCount() const;
  std::vector<io::PickedPoint> Pairs() const;  // complete pairs, each point in its scan's frame
  bool Levelled() const;
  QString Status() const;  // what is missing, or the fit's RMS
  QCheckBox* levelledBox() const { return levelled_; }
  QTableWidget* table() const { return table_; }
  QPushButton* alignButton() const { return align_; }

 private:
  struct Cell {
    int row = 0, col = 0;
  };
  void ShowScans();
  void Update();  // markers, table, status
  const Scan* FindScan(const QString& name) const;

  FetchScan fetch_;
  std::optional<Scan> parent_scan_, child_scan_;
  QString read_error_;  // why a scan shown could not be read
  QString child_name_;
  QComboBox* parent_box_ = nullptr;
  ZoomView* parent_view_ = nullptr;
  ZoomView* child_view_ = nullptr;
  QGraphicsScene* parent_scene_ = nullptr;
  QGraphicsScene* child_scene_ = nullptr;
  QTableWidget* table_ = nullptr;
  QCheckBox* levelled_ = nullptr;
  QLabel* status_ = nullptr;
  QPushButton* align_ = nullptr;
  std::vector<Cell> parent_picks_, child_picks_;
  std::vector<bool> pick_order_parent_;  // for "remove last": which side each pick was on
};

}  // namespace scanreg::ui
