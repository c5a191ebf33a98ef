// The pair panel: choose a pair (parent and child scan) and the coarse and fine methods, run the
// pair registration (on the worker, through PairInspector), read its evidence (matches, inliers,
// RMS, overlap, conflict, iterations, time, status and reason) and, with reference poses, the
// errors; "Use this result" applies it to the project as an undoable edit; "Show project" puts
// the project's scans back in the 3D view after the distance preview.
#pragma once

#include <QMap>
#include <QString>
#include <QStringList>
#include <QWidget>

#include "core/pipeline/inspect_pair.h"
#include "core/pipeline/register_options.h"

class QComboBox;
class QLabel;
class QPushButton;

namespace scanreg::ui {

class PairPanel : public QWidget {
  Q_OBJECT

 public:
  explicit PairPanel(QWidget* parent = nullptr);

  void SetScans(const QStringList& names);  // keeps the selected pair when its scans remain
  void SetPair(const QString& parent, const QString& child);
  void SetMethods(CoarseMethod coarse, pipeline::FineMethod fine);
  QString parentScan() const;
  QString childScan() const;
  CoarseMethod coarseMethod() const;
  pipeline::FineMethod fineMethod() const;

  void SetRunning(bool running);
  void ShowResult(const pipeline::PairInspection& result);
  void ShowMessage(const QString& status, const QString& reason);  // clears the evidence
  // A link as the project stores it (no run): its evidence, and `note` where the errors against the
  // reference go (a stored link says where it came from; Run registers the pair again).
  void ShowStoredLink(const io::LinkRecord& link, const QString& note);
  // The text of an evidence field: "status", "reason", "method", "matches", "reliable", "inliers",
  // "consistent", "rms", "overlap", "conflict", "iterations", "time", "error", "coarse_error".
  QString Evidence(const QString& field) const;

  QPushButton* runButton() const { return run_; }
  QPushButton* cancelButton() const { return cancel_; }
  QPushButton* useButton() const { return use_; }
  QPushButton* refineButton() const { return refine_; }

 signals:
  void RunRequested();
  void CancelRequested();
  void UseResultRequested();
  void RefineRequested();
  void ShowProjectRequested();

 private:
  void SetField(const QString& field, const QString& text);
  void ShowLinkFields(const io::LinkRecord& link);

  QComboBox* parent_ = nullptr;
  QComboBox* child_ = nullptr;
  QComboBox* coarse_ = nullptr;
  QComboBox* fine_ = nullptr;
  QPushButton* run_ = nullptr;
  QPushButton* cancel_ = nullptr;
  QPushButton* use_ = nullptr;
  QPushButton* show_project_ = nullptr;
  QPushButton* refine_ = nullptr;
  QMap<QString, QLabel*> fields_;
};

}  // namespace scanreg::ui
