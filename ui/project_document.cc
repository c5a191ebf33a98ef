#include "ui/project_document.h"

#include <QUndoCommand>
#include <QUndoStack>

#include "core/pipeline/project_scans.h"

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

std::shared_ptr<pipeline::ScanStore> ProjectDocument::FullScans() const {
  // new, not make_shared: the store (a mutex) is built in place from ProjectScanStore's value.
  return std::shared_ptr<pipeline::ScanStore>(
      new pipeline::ScanStore(pipeline::ProjectScanStore(project_, pipeline::DefaultMemoryBudget())));
}

Expected<Scan> ProjectDocument::ReadScan(int i) const {
  NullProgress quiet;
  Expected<std::vector<Scan>> one = pipeline::LoadProjectScans(project_, quiet, CancelToken(), {i});
  if (!one) return one.error();
  return std::move(one->front());
}

void ProjectDocument::SyncPoses() {
  for (std::size_t i = 0; i < previews_.size() && i < project_.scans.size(); ++i) {
    previews_[i].scan.world_from_scan = project_.scans[i].world_from_scan;
    previews_[i].scan.name = project_.scans[i].name;
  }
}

void ProjectDocument::SyncScans(const io::Project& before) {
  bool same = before.scans.size() == project_.scans.size();
  for (std::size_t i = 0; same && i < project_.scans.size(); ++i) same = KeyOf(before.scans[i]) == KeyOf(project_.scans[i]);
  if (!same) {
    for (std::size_t i = 0; i < previews_.size() && i < before.scans.size(); ++i)
      set_aside_[KeyOf(before.scans[i])] = std::move(previews_[i]);
    previews_.clear();
    for (const io::ProjectScan& ps : project_.scans) {
      auto it = set_aside_.find(KeyOf(ps));
      if (it == set_aside_.end()) {  // cannot happen: every scan of an edit was read before
        previews_.push_back(pipeline::ScanPreview{Scan(ps.name, 0, 0)});
        continue;
      }
      previews_.push_back(std::move(it->second));
      set_aside_.erase(it);
    }
  }
  SyncPoses();
  if (!same) emit ScansChanged();
}

void ProjectDocument::Open(io::Project project, std::vector<pipeline::ScanPreview> previews) {
  project_ = std::move(project);
  previews_ = std::move(previews);
  set_aside_.clear();
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

void ProjectDocument::AppendScans(io::Project project, std::vector<pipeline::ScanPreview> added) {
  project_ = std::move(project);
  for (pipeline::ScanPreview& s : added) previews_.push_back(std::move(s));
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

void ProjectDocument::EditWithScan(const QString& text, io::Project after, pipeline::ScanPreview scan) {
  for (const io::ProjectScan& ps : after.scans)
    if (ps.name == scan.scan.name) set_aside_[KeyOf(ps)] = std::move(scan);
  Edit(text, std::move(after));
}

void ProjectDocument::ApplyRegistration(const QString& text, io::Project after, Eigen::MatrixXi confusion) {
  // Merged into the edit that asked for this run, when that edit is the last step.
  undo_->push(
      new SnapshotCommand(this, text, project_, std::move(after), confusion_, std::move(confusion), false, true));
}

void ProjectDocument::Replace(const io::Project& project, const Eigen::MatrixXi& confusion) {
  const std::filesystem::path file = project_.file;
  const std::uint64_t digest = project_.disk_digest;
  const io::Project before = std::move(project_);
  project_ = project;
  project_.file = file;  // where the project lives is not part of an edit
  project_.disk_digest = digest;
  confusion_ = confusion;
  SyncScans(before);
  emit PosesChanged();
  emit Changed();
  NotifyDirty();
}

void ProjectDocument::MarkChanged() {
  scans_added_ = true;
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
