#include "ui/project_document.h"

#include <QUndoCommand>
#include <QUndoStack>

namespace scanreg::ui {

// One edit, undone by restoring the snapshot from before it (projects hold no points: cheap). An
// edit that asked for the registration to run again takes that run's result into the same step:
// one undo takes back the override and what it changed.
class SnapshotCommand : public QUndoCommand {
 public:
  static constexpr int kAwaitingRerun = 1;  // QUndoCommand::id of an edit waiting for its rerun's result

  SnapshotCommand(ProjectDocument* doc, const QString& text, io::Project before, io::Project after,
                  Eigen::MatrixXi confusion_before, Eigen::MatrixXi confusion_after, bool rerun, bool rerun_result)
      : QUndoCommand(text),
        doc_(doc),
        before_(std::move(before)),
        after_(std::move(after)),
        confusion_before_(std::move(confusion_before)),
        confusion_after_(std::move(confusion_after)),
        rerun_(rerun),
        awaiting_(rerun || rerun_result) {}
  int id() const override { return awaiting_ ? kAwaitingRerun : -1; }
  bool mergeWith(const QUndoCommand* other) override {
    const auto* result = static_cast<const SnapshotCommand*>(other);
    if (!rerun_ || result->rerun_) return false;  // only an edit takes its rerun's result
    after_ = result->after_;
    confusion_after_ = result->confusion_after_;
    awaiting_ = false;
    return true;
  }
  void undo() override { doc_->Replace(before_, confusion_before_); }
  void redo() override {
    doc_->Replace(after_, confusion_after_);
    if (rerun_ && awaiting_ && first_) emit doc_->RerunRequested();  // not again on a redo
    first_ = false;
  }

 private:
  ProjectDocument* doc_;
  io::Project before_, after_;
  Eigen::MatrixXi confusion_before_, confusion_after_;
  bool rerun_;
  bool awaiting_;
  bool first_ = true;
};

ProjectDocument::ProjectDocument(QObject* parent) : QObject(parent), undo_(new QUndoStack(this)) {
  connect(undo_, &QUndoStack::cleanChanged, this, [this] { NotifyDirty(); });
}

bool ProjectDocument::dirty() const { return scans_added_ || !undo_->isClean(); }

void ProjectDocument::NotifyDirty() {
  if (dirty() == was_dirty_) return;
  was_dirty_ = dirty();
  emit DirtyChanged(was_dirty_);
}

void ProjectDocument::SyncPoses() {
  for (std::size_t i = 0; i < scans_.size() && i < project_.scans.size(); ++i)
    scans_[i].world_from_scan = project_.scans[i].world_from_scan;
}

void ProjectDocument::Open(io::Project project, std::vector<Scan> scans) {
  project_ = std::move(project);
  scans_ = std::move(scans);
  SyncPoses();
  const Eigen::MatrixXi* saved = project_.CurrentConfusion();  // from the last registration, if any
  confusion_ = saved ? *saved : Eigen::MatrixXi();
  undo_->clear();
  scans_added_ = false;
  emit Opened();
  emit ScansChanged();
  emit PosesChanged();
  emit Changed();
  NotifyDirty();
}

void ProjectDocument::AppendScans(io::Project project, std::vector<Scan> added) {
  project_ = std::move(project);
  for (Scan& s : added) scans_.push_back(std::move(s));
  SyncPoses();
  confusion_.resize(0, 0);
  undo_->clear();
  scans_added_ = true;
  emit ScansChanged();
  emit PosesChanged();
  emit Changed();
  NotifyDirty();
}

void ProjectDocument::Edit(const QString& text, io::Project after, bool rerun) {
  undo_->push(new SnapshotCommand(this, text, project_, std::move(after), confusion_, confusion_, rerun, false));
}

void ProjectDocument::ApplyRegistration(const QString& text, io::Project after, Eigen::MatrixXi confusion) {
  // Merged into the edit that asked for this run, when that edit is the last step.
  undo_->push(
      new SnapshotCommand(this, text, project_, std::move(after), confusion_, std::move(confusion), false, true));
}

void ProjectDocument::Replace(const io::Project& project, const Eigen::MatrixXi& confusion) {
  const std::filesystem::path file = project_.file;
  const std::uint64_t digest = project_.disk_digest;
  project_ = project;
  project_.file = file;  // where the project lives is not part of an edit
  project_.disk_digest = digest;
  confusion_ = confusion;
  SyncPoses();
  emit PosesChanged();
  emit Changed();
  NotifyDirty();
}

void ProjectDocument::MarkSaved(const std::filesystem::path& file, std::uint64_t digest) {
  project_.file = file;
  project_.disk_digest = digest;
  scans_added_ = false;
  undo_->setClean();
  NotifyDirty();
  emit Changed();  // the title shows the file
}

}  // namespace scanreg::ui
