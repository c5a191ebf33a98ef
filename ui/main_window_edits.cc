// MainWindow's edits of the project on the user's behalf (issue 14): placing scans by hand,
// aligning them by picked points or refining them from where they stand, parent overrides and link
// decisions, registering only what is missing, and project management (remove, rename, relink, root).
// Split from main_window.cc, which builds the window, its menus and the file actions.
#include <QApplication>
#include <QStatusBar>

#include "core/common/log.h"
#include "core/io/project_tree.h"
#include "core/pipeline/manual_alignment.h"
#include "core/pipeline/project_edits.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/refine_pair.h"
#include "core/pipeline/register_project.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"

#include "core/io/control_file.h"
#include "ui/pick_points_dialog.h"
#include "ui/pose_dialog.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"

namespace scanreg::ui {

bool MainWindow::RegisterUnregistered() {
  pipeline::RegisterOptions options = RegistrationOptions();
  for (const io::ProjectScan& s : project().scans)
    if (!s.registered) options.only_scans.push_back(s.name);
  if (options.only_scans.empty()) {
    statusBar()->showMessage(tr("Every scan is registered: nothing to add"), 8000);
    return false;
  }
  return StartRegistration(tr("register the unregistered scans"), options, false);
}

bool MainWindow::RefineFromCurrentPoses() {
  pipeline::RegisterOptions options = RegistrationOptions();
  options.from_current_poses = true;
  return StartRegistration(tr("refine every scan from its current pose"), options, false);
}

QString MainWindow::SelectedScan() const {
  const QTableWidgetItem* item = scan_list_->item(scan_list_->currentRow(), 0);
  return item ? item->text() : QString();
}

namespace {

// The registered scan a scan is refined or aligned to: its tree parent, else the registered scans
// nearest to where it stands first.
QStringList ParentCandidates(const io::Project& project, const std::string& child) {
  const int c = project.FindScan(child);
  std::vector<std::pair<double, std::string>> near;
  std::string tree_parent;
  for (const io::LinkRecord& l : project.links)
    if (io::IsTreeLink(l) && l.child == child) tree_parent = l.parent;
  for (const io::ProjectScan& s : project.scans) {
    if (!s.registered || s.name == child) continue;
    const double d = s.name == tree_parent ? -1.0
                                           : (s.world_from_scan.translation() -
                                              project.scans[c].world_from_scan.translation()).norm();
    near.emplace_back(d, s.name);
  }
  std::sort(near.begin(), near.end());
  QStringList out;
  for (const auto& [d, name] : near) out << QString::fromStdString(name);
  return out;
}

}  // namespace

bool MainWindow::StartPairJob(const QString& title,
                              std::function<Expected<io::LinkRecord>(ProgressSink&, const CancelToken&)> job) {
  return jobs_->Start<io::LinkRecord>(title, std::move(job), [this, title](io::LinkRecord& link) {
    const QString pair = QString::fromStdString(link.child + " → " + link.parent);
    if (link.status == io::LinkStatus::kFailed) {
      ShowError(title, tr("%1 failed: %2\n\nThe project is unchanged.").arg(pair, QString::fromStdString(link.reason)));
      return;
    }
    if (UsePairResult(link)) {
      last_summary_ = tr("%1: %2, RMS %3 mm, overlap %4 %")
                          .arg(pair, io::LinkStatusName(link.status))
                          .arg(1e3 * link.rms_m, 0, 'f', 1)
                          .arg(100 * link.overlap, 0, 'f', 0);
      LogInfo(last_summary_.toStdString());
    }
  });
}

bool MainWindow::RefineScan(const QString& scan, const QString& parent) {
  QStringList parents = ParentCandidates(project(), scan.toStdString());
  if (!parent.isEmpty()) parents = parents.contains(parent) ? QStringList{parent} : QStringList{};
  const int c = project().FindScan(scan.toStdString());
  if (c < 0 || parents.isEmpty() || project().root == scan.toStdString()) {
    ShowError(tr("Refine scan"), c < 0 ? tr("Select a scan in the scan list first.")
                                 : project().root == scan.toStdString()
                                     ? tr("%1 is the root: the other scans are refined to it.").arg(scan)
                                 : !parent.isEmpty()
                                     ? tr("%1 is not registered: refine %2 against a registered scan.").arg(parent, scan)
                                     : tr("No registered scan to refine %1 against: register or place one first.").arg(scan));
    return false;
  }
  const int p = project().FindScan(parents.first().toStdString());
  return StartPairJob(tr("Refining %1 to %2").arg(scan, parents.first()),
                      [scans = doc_->FullScans(), p, c, options = RegistrationOptions()](
                          ProgressSink&, const CancelToken& cancel) -> Expected<io::LinkRecord> {
                        auto parent = scans->Get(p);
                        if (!parent) return parent.error();
                        auto child = scans->Get(c);
                        if (!child) return child.error();
                        const Eigen::Isometry3d start =
                            (*parent)->world_from_scan.inverse() * (*child)->world_from_scan;
                        return pipeline::RefinePairFromPose(**parent, **child, start, options, 0.0, cancel);
                      });
}

PickPointsDialog* MainWindow::PickPoints(const QString& child) {
  const QStringList parents = ParentCandidates(project(), child.toStdString());
  if (project().FindScan(child.toStdString()) < 0 || parents.isEmpty()) {
    ShowError(tr("Align by picked points"), parents.isEmpty() && !child.isEmpty()
                                                ? tr("No registered scan to align %1 to: register or place one first.").arg(child)
                                                : tr("Select the scan to align in the scan list first."));
    return nullptr;
  }
  // The full scans, read when the dialog shows them (cells are picked at full resolution).
  auto fetch = [this](const QString& name) -> Expected<Scan> {
    QApplication::setOverrideCursor(Qt::WaitCursor);
    Expected<Scan> scan = doc_->ReadScan(project().FindScan(name.toStdString()));
    QApplication::restoreOverrideCursor();
    return scan;
  };
  auto* dialog = new PickPointsDialog(fetch, child, parents, this);
  dialog->setAttribute(Qt::WA_DeleteOnClose);
  connect(dialog, &QDialog::accepted, this, [this, dialog] {
    AlignFromPickedPoints(dialog->ParentScan(), dialog->ChildScan(), dialog->Pairs(), dialog->Levelled());
  });
  dialog->open();
  return dialog;
}

bool MainWindow::AlignFromPickedPoints(const QString& parent, const QString& child,
                                       std::vector<io::PickedPoint> pairs, bool levelled) {
  const int p = project().FindScan(parent.toStdString()), c = project().FindScan(child.toStdString());
  if (p < 0 || c < 0) return false;
  return StartPairJob(tr("Aligning %1 to %2 by picked points").arg(child, parent),
                      [scans = doc_->FullScans(), p, c, pairs = std::move(pairs), levelled,
                       options = RegistrationOptions()](ProgressSink&, const CancelToken& cancel) -> Expected<io::LinkRecord> {
                        auto parent = scans->Get(p);
                        if (!parent) return parent.error();
                        auto child = scans->Get(c);
                        if (!child) return child.error();
                        return pipeline::AlignFromPickedPoints(**parent, **child, pairs, levelled, options, cancel);
                      });
}

bool MainWindow::SetParentOverride(const QString& child, const QString& parent) {
  const int c = project().FindScan(child.toStdString());
  if (c < 0 || child == parent || (!parent.isEmpty() && project().FindScan(parent.toStdString()) < 0)) return false;
  const QString text =
      parent.isEmpty() ? tr("clear the parent of %1").arg(child) : tr("register %1 to %2").arg(child, parent);
  std::optional<std::string> chosen;
  if (!parent.isEmpty()) chosen = parent.toStdString();
  struct Overridden {
    io::Project project;
    pipeline::OverrideOutcome outcome;
  };
  return jobs_->Start<Overridden>(
      tr("Registering %1").arg(child),
      [project = project(), scans = doc_->FullScans(), options = RegistrationOptions(), name = child.toStdString(), chosen](
          ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<Overridden> {
        Expected<pipeline::OverrideOutcome> out =
            pipeline::OverrideParent(project, *scans, name, chosen, options, progress, cancel);
        if (!out) return out.error();
        return Overridden{std::move(project), std::move(*out)};
      },
      [this, text](Overridden& r) {
        const QString message = QString::fromStdString(r.outcome.message);
        if (!r.outcome.applied) {
          ShowError(tr("The link you asked for failed"), message);
          return;
        }
        doc_->ApplyRegistration(text, std::move(r.project), r.outcome.confusion);
        ReportRegistration();
        last_summary_ = message + "; " + last_summary_;
      });
}

void MainWindow::SetLinkDecision(const QString& parent, const QString& child, bool accept, bool reject) {
  io::Project after = project();
  const pipeline::LinkDecision decision = reject   ? pipeline::LinkDecision::kReject
                                          : accept ? pipeline::LinkDecision::kAccept
                                                   : pipeline::LinkDecision::kClear;
  if (!pipeline::SetLinkDecision(parent.toStdString(), child.toStdString(), decision, after)) return;
  const QString text = reject   ? tr("reject %1 → %2").arg(child, parent)
                       : accept ? tr("accept %1 → %2").arg(child, parent)
                                : tr("clear the decision on %1 → %2").arg(child, parent);
  doc_->Edit(text, std::move(after), reject);
}

bool MainWindow::SetScanPose(const QString& scan, const Eigen::Isometry3d& world_from_scan, bool move_dependents) {
  io::Project after = project();
  if (Status s = pipeline::SetScanPose(scan.toStdString(), world_from_scan, move_dependents, after); !s) {
    ShowError(tr("Cannot place %1").arg(scan), QString::fromStdString(s.error().message));
    return false;
  }
  doc_->Edit(tr("place %1 by hand").arg(scan), std::move(after));
  return true;
}

bool MainWindow::ReleaseHandPlacement(const QString& scan) {
  io::Project after = project();
  if (Status s = pipeline::ReleaseHandPlacement(scan.toStdString(), after); !s) {
    ShowError(tr("Release hand placement"), QString::fromStdString(s.error().message));
    return false;
  }
  doc_->Edit(tr("release the hand placement of %1").arg(scan), std::move(after));
  return true;
}

PoseDialog* MainWindow::EditSelectedScanPose() {
  const QTableWidgetItem* item = scan_list_->item(scan_list_->currentRow(), 0);
  const int s = item ? project().FindScan(item->text().toStdString()) : -1;
  if (s < 0) {
    ShowError(tr("Edit scan pose"),
              tr("Select a scan in the scan list first, then choose Registration → Edit scan pose."));
    return nullptr;
  }
  const QString name = item->text();
  auto* dialog = new PoseDialog(name, project().scans[s].world_from_scan, this);
  dialog->setAttribute(Qt::WA_DeleteOnClose);
  connect(dialog, &QDialog::accepted, this,
          [this, dialog, name] { SetScanPose(name, dialog->Pose(), dialog->MoveDependents()); });
  dialog->open();
  return dialog;
}

bool MainWindow::UsePairResult(const io::LinkRecord& link) {
  io::Project after = project();
  if (Status s = pipeline::ApplyPairResult(link, after); !s) {
    ShowError(tr("Cannot use this pair registration"), QString::fromStdString(s.error().message));
    return false;
  }
  const QString text = tr("use the pair registration %1 → %2 (%3)")
                           .arg(QString::fromStdString(link.child), QString::fromStdString(link.parent),
                                QString::fromStdString(link.method));
  doc_->Edit(text, std::move(after));
  return true;
}

bool MainWindow::RemoveScan(const QString& scan) {
  io::Project after = project();
  Expected<std::vector<std::string>> orphans = pipeline::RemoveScan(scan.toStdString(), after);
  if (!orphans) {
    ShowError(tr("Remove scan"), QString::fromStdString(orphans.error().message));
    return false;
  }
  doc_->Edit(tr("remove %1").arg(scan), std::move(after));
  QString said = tr("Removed %1 (Edit → Undo brings it back)").arg(scan);
  if (!orphans->empty()) {
    QStringList names;
    for (const std::string& n : *orphans) names << QString::fromStdString(n);
    said += tr("; %1 were registered through it and keep their poses without a link: register again to link them")
                .arg(names.join(", "));
  }
  LogInfo(said.toStdString());
  statusBar()->showMessage(said, 12000);
  return true;
}

bool MainWindow::RenameScan(const QString& scan, const QString& new_name) {
  io::Project after = project();
  if (Status s = pipeline::RenameScan(scan.toStdString(), new_name.trimmed().toStdString(), after); !s) {
    ShowError(tr("Rename scan"), QString::fromStdString(s.error().message));
    return false;
  }
  doc_->Edit(tr("rename %1 to %2").arg(scan, new_name.trimmed()), std::move(after));
  return true;
}

bool MainWindow::SetRoot(const QString& scan) {
  io::Project after = project();
  if (Status s = pipeline::SetRoot(scan.toStdString(), after); !s) {
    ShowError(tr("Set root"), QString::fromStdString(s.error().message));
    return false;
  }
  doc_->Edit(tr("make %1 the root").arg(scan), std::move(after));
  statusBar()->showMessage(tr("%1 is the root: the next registration keeps its pose and places the others from it").arg(scan), 12000);
  return true;
}

bool MainWindow::RelinkScan(const QString& scan, const QString& file) {
  const int s = project().FindScan(scan.toStdString());
  if (s < 0) return false;
  struct Relinked {
    io::Project project;
    pipeline::ScanPreview scan;
  };
  // The grid the scan had, to check that the new file holds the same scan.
  Scan current(scan.toStdString(), 0, 0);
  current.rows = previews()[s].full_rows;
  current.cols = previews()[s].full_cols;
  return jobs_->Start<Relinked>(
      tr("Relinking %1").arg(scan),
      [project = project(), current = std::move(current), name = scan.toStdString(), path = file.toStdString(),
       cells = pipeline::PreviewCellsPerScan(project().scans.size(), doc_->previewCells())](
          ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<Relinked> {
        Expected<Scan> read = pipeline::RelinkScan(project, name, path, &current, progress, cancel);
        if (!read) return read.error();
        return Relinked{std::move(project),
                        pipeline::MakePreview(std::move(*read), cells)};
      },
      [this, scan, file](Relinked& r) {
        doc_->EditWithScan(tr("relink %1 to %2").arg(scan, file), std::move(r.project), std::move(r.scan));
      });
}

}  // namespace scanreg::ui
