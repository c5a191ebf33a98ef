// The open project as the window and every panel see it (issue 14 item 1): the project — where the
// poses are stored, once —, its scans' points, the confusion matrix of the last registration, the
// undo stack and whether it differs from the file. Panels observe its signals instead of being
// told by the window; every change goes through it, most as an undoable snapshot of the project.
#pragma once

#include <Eigen/Core>
#include <QObject>
#include <QString>
#include <cstdint>
#include <filesystem>
#include <map>
#include <utility>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"

class QUndoStack;

namespace scanreg::ui {

class ProjectDocument : public QObject {
  Q_OBJECT

 public:
  explicit ProjectDocument(QObject* parent = nullptr);

  const io::Project& project() const { return project_; }
  // The scans' points, in project order; each world_from_scan equals the project's pose.
  const std::vector<Scan>& scans() const { return scans_; }
  const Eigen::MatrixXi& confusion() const { return confusion_; }
  QUndoStack* undoStack() const { return undo_; }
  // Unsaved changes: an edit since the last save or load that undo has not taken back, or scans
  // added (not undoable).
  bool dirty() const;

  // Another project (opened, created, reloaded): no undo history, not dirty. Emits Opened.
  void Open(io::Project project, std::vector<Scan> scans);
  // Scans read into the open project (`project` holds them appended): not undoable (the undo
  // history, whose snapshots hold fewer scans, is cleared).
  void AppendScans(io::Project project, std::vector<Scan> added);
  // An undoable edit from the current project to `after` (an override, a decision, a pose, a
  // registration's result). rerun: the registration should run again after it (not on undo/redo).
  void Edit(const QString& text, io::Project after, bool rerun = false);
  // An undoable edit that points a scan at another file (relink): `scan` holds the points read from
  // it, kept for as long as the project is open (undo points back to the old file's points).
  void EditWithScan(const QString& text, io::Project after, Scan scan);
  // A registration's result: an undoable edit that also replaces the confusion matrix.
  void ApplyRegistration(const QString& text, io::Project after, Eigen::MatrixXi confusion);
  // The project differs from its file though nothing was edited (relinked while opening).
  void MarkChanged();
  // The project was written to `file` with this content digest: clean from here.
  void MarkSaved(const std::filesystem::path& file, std::uint64_t digest);

 signals:
  void Opened();            // a different project: views reset their camera and panels
  void ScansChanged();      // scans were added, removed or relinked (clouds to build)
  void PosesChanged();      // poses changed: derived results (a merged mesh) no longer match
  void Changed();           // anything shown changed: redraw
  void DirtyChanged(bool dirty);
  void RerunRequested();    // an edit asked for the registration to run again

 private:
  friend class SnapshotCommand;
  void Replace(const io::Project& project, const Eigen::MatrixXi& confusion);  // undo / redo
  // scans_ follows project_: each scan's points by (file, index in file), from the scans shown or
  // the ones kept aside (a removed scan, an old file after relink: undo brings them back).
  using ScanKey = std::pair<std::filesystem::path, int>;
  static ScanKey KeyOf(const io::ProjectScan& s) { return {s.path, s.index_in_file}; }
  void SyncScans(const io::Project& before);
  void SyncPoses();
  void NotifyDirty();

  io::Project project_;
  std::vector<Scan> scans_;
  std::map<ScanKey, Scan> set_aside_;
  Eigen::MatrixXi confusion_;
  QUndoStack* undo_ = nullptr;
  bool scans_added_ = false;  // scans added or files relinked since the last save or load (not undoable)
  bool was_dirty_ = false;
};

}  // namespace scanreg::ui
