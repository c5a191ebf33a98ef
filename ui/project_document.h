// The open project as the window and every panel see it (issue 14 item 1): the project — where the
// poses are stored, once —, its scans' previews (what the views draw; the full points are read from
// the scans' files when a job or a dialog needs them: issue 13), the confusion matrix of the last registration, the
// undo stack and whether it differs from the file. Panels observe its signals instead of being
// told by the window; every change goes through it, most as an undoable snapshot of the project.
#pragma once

#include <Eigen/Core>
#include <QObject>
#include <QString>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "core/common/expected.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/scan_previews.h"
#include "core/pipeline/scan_store.h"

class QUndoStack;

namespace scanreg::ui {

class ProjectDocument : public QObject {
  Q_OBJECT

 public:
  explicit ProjectDocument(QObject* parent = nullptr);

  const io::Project& project() const { return project_; }
  // The scans' previews, in project order; each preview's world_from_scan equals the project's pose.
  const std::vector<pipeline::ScanPreview>& previews() const { return previews_; }
  // The full scans of the project as it stands (names, poses), read from their files (the binary
  // scan cache) on demand and dropped beyond the memory budget: a job's own store.
  std::shared_ptr<pipeline::ScanStore> FullScans() const;
  // Scan i in full, read now (a dialog that picks cells). Errors name the scan and its file.
  Expected<Scan> ReadScan(int i) const;
  // The cells all previews share (pipeline::kPreviewCells; tests set fewer).
  std::size_t previewCells() const { return preview_cells_; }
  void SetPreviewCells(std::size_t cells) { preview_cells_ = cells; }
  const Eigen::MatrixXi& confusion() const { return confusion_; }
  QUndoStack* undoStack() const { return undo_; }
  // Unsaved changes: an edit since the last save or load that undo has not taken back, or scans
  // added (not undoable).
  bool dirty() const;

  // Another project (opened, created, reloaded): no undo history, not dirty. Emits Opened.
  void Open(io::Project project, std::vector<pipeline::ScanPreview> previews);
  // Scans read into the open project (`project` holds them appended): not undoable (the undo
  // history, whose snapshots hold fewer scans, is cleared).
  void AppendScans(io::Project project, std::vector<pipeline::ScanPreview> added);
  // An undoable edit from the current project to `after` (an override, a decision, a pose, a
  // registration's result). rerun: the registration should run again after it (not on undo/redo).
  void Edit(const QString& text, io::Project after, bool rerun = false);
  // An undoable edit that points a scan at another file (relink): `scan` is the preview of the points
  // read from it, kept for as long as the project is open (undo points back to the old file's).
  void EditWithScan(const QString& text, io::Project after, pipeline::ScanPreview scan);
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
  // previews_ follows project_: each scan's preview by (file, index in file), from the ones shown or
  // the ones kept aside (a removed scan, an old file after relink: undo brings them back).
  using ScanKey = std::pair<std::filesystem::path, int>;
  static ScanKey KeyOf(const io::ProjectScan& s) { return {s.path, s.index_in_file}; }
  void SyncScans(const io::Project& before);
  void SyncPoses();
  void NotifyDirty();

  io::Project project_;
  std::vector<pipeline::ScanPreview> previews_;
  std::map<ScanKey, pipeline::ScanPreview> set_aside_;
  Eigen::MatrixXi confusion_;
  QUndoStack* undo_ = nullptr;
  std::size_t preview_cells_ = pipeline::kPreviewCells;
  bool scans_added_ = false;  // scans added or files relinked since the last save or load (not undoable)
  bool was_dirty_ = false;
};

}  // namespace scanreg::ui
