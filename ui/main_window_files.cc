// The main window's project files: opening (with moved scan files found again), creating, adding
// scans, the demo project, saving (atomic, under the project's lock; a project changed on disk is
// not overwritten) and the report. The files are read on the worker.
#include <QFileDialog>
#include <QMessageBox>
#include <QPushButton>
#include <QStatusBar>
#include <QTimer>

#include "core/common/log.h"
#include "core/io/project_lock.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/report/report.h"
#include "ui/app_settings.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/project_document.h"

namespace scanreg::ui {
namespace {

struct LoadedProject {
  io::Project project;
  std::vector<pipeline::ScanPreview> previews;
};

// Scans read for the open project (Add scans): the project with them appended, and their previews.
struct AddedScans {
  io::Project project;
  std::vector<pipeline::ScanPreview> previews;
  std::vector<std::string> skipped;  // why each file left out was left out
};

// The project's previews, one scan in memory at a time (issue 13: the desktop keeps previews).
// preview_cells: what all previews share.
Expected<LoadedProject> LoadJob(io::Project project, std::size_t preview_cells, ProgressSink& progress,
                                const CancelToken& cancel) {
  Expected<std::vector<pipeline::ScanPreview>> previews = pipeline::LoadScanPreviews(
      project, pipeline::PreviewCellsPerScan(project.scans.size(), preview_cells), progress, cancel);
  if (!previews) return previews.error();
  return LoadedProject{std::move(project), std::move(*previews)};
}

}  // namespace

bool MainWindow::OpenProject(const QString& path, const QString& scan_folder) {
  Expected<io::Project> project = io::LoadProject(path.toStdString());
  if (!project) {
    ShowError(tr("Cannot open project"), QString::fromStdString(project.error().message));
    return false;
  }
  // Scan files that moved: looked for in scan_folder, or the user is asked for a folder.
  const bool relinked = !scan_folder.isEmpty() && pipeline::RelinkFromFolder(*project, scan_folder.toStdString()) > 0;
  const std::vector<std::string> missing = pipeline::MissingScanFiles(*project);
  if (!missing.empty()) {
    QStringList lines;
    for (const std::string& name : missing)
      lines << QString::fromStdString(name + ": " + project->scans[project->FindScan(name)].path.string());
    auto* box = new QMessageBox(QMessageBox::Warning, tr("Scan files missing"),
                                tr("%n scan file(s) of %1 are not where the project says:\n\n%2\n\nLocate the folder "
                                   "that holds them (the project is relinked to it; save to keep the new paths).",
                                   "", int(missing.size()))
                                    .arg(path, lines.join("\n")),
                                QMessageBox::Cancel, this);
    box->setObjectName("MissingFilesDialog");
    box->setAttribute(Qt::WA_DeleteOnClose);
    QPushButton* locate = box->addButton(tr("Locate folder…"), QMessageBox::AcceptRole);
    connect(locate, &QPushButton::clicked, this, [this, path] {
      const QString dir = QFileDialog::getExistingDirectory(this, tr("Folder with the missing scan files"), LastDir());
      if (!dir.isEmpty()) QTimer::singleShot(0, this, [this, path, dir] { OpenProject(path, dir); });
    });
    LogWarning(QString("%1: %2 scan file(s) missing").arg(path).arg(missing.size()).toStdString());
    box->open();
    return false;
  }
  return jobs_->Start<LoadedProject>(
      tr("Loading %1").arg(path),
      [p = std::move(*project), cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) {
        return LoadJob(p, cells, progress, cancel);
      },
      [this, relinked](LoadedProject& loaded) {
        OnProjectLoaded(std::move(loaded.project), std::move(loaded.previews));
        if (relinked) doc_->MarkChanged();  // the new paths are not saved yet
      });
}

void MainWindow::OnProjectLoaded(io::Project project, std::vector<pipeline::ScanPreview> previews) {
  doc_->Open(std::move(project), std::move(previews));
  if (!this->project().file.empty()) AddRecentProject(QString::fromStdString(this->project().file.string()));
}

bool MainWindow::OpenDemoProject(const QString& dir) {
  return jobs_->Start<LoadedProject>(
      tr("Simulating the demo project"),
      [dir, cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) -> Expected<LoadedProject> {
    SimulatedProjectOptions options;
    options.stations = 5;
    options.scanner.cols = 1500;
    options.scanner.rows = 375;
    SubProgress sim(progress, 0.0, 0.7);
    Expected<io::Project> project = pipeline::WriteSimulatedProject(options, dir.toStdString(), sim, cancel);
    if (!project) return project.error();
    SubProgress load(progress, 0.7, 1.0);
    return LoadJob(std::move(*project), cells, load, cancel);
      },
      [this](LoadedProject& loaded) { OnProjectLoaded(std::move(loaded.project), std::move(loaded.previews)); });
}

void MainWindow::SaveProjectAs() {
  QString path = QFileDialog::getSaveFileName(this, tr("Save project as"), LastDir(),
                                              tr("scanreg projects (*.scanreg.json)"));
  if (path.isEmpty()) return;
  // Open lists *.scanreg.json: a project saved under another name would be hidden from it.
  if (!path.endsWith(".scanreg.json")) path += path.endsWith(".json") ? QString() : QStringLiteral(".scanreg.json");
  RememberDir(path);
  SaveProject(path);
}

bool MainWindow::SaveProject(const QString& path) {
  // One writer per project (issue 16): a `scanreg-cli register` running on it holds its lock.
  Expected<io::ProjectLock> lock = io::ProjectLock::Acquire(path.toStdString(), "scanreg (saving from the GUI)");
  if (!lock) {
    ShowError(tr("Cannot save project"), QString::fromStdString(lock.error().message));
    return false;
  }
  std::uint64_t digest = 0;
  if (Status s = io::SaveProject(project(), path.toStdString(), &digest); !s) {
    if (s.error().code == ErrorCode::kConflict) {
      OfferReload(path, QString::fromStdString(s.error().message));
    } else {
      ShowError(tr("Cannot save project"), QString::fromStdString(s.error().message));
    }
    return false;
  }
  doc_->MarkSaved(std::filesystem::absolute(path.toStdString()), digest);
  statusBar()->showMessage(tr("Saved %1").arg(path), 5000);
  return true;
}

void MainWindow::OfferReload(const QString& path, const QString& message) {
  LogWarning(message.toStdString());
  auto* box = new QMessageBox(QMessageBox::Warning, tr("The project changed on disk"),
                              message + tr("\n\nReload it (your unsaved changes are lost), save your version under "
                                           "another name, or cancel and decide later."),
                              QMessageBox::NoButton, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ConflictDialog");
  QPushButton* reload = box->addButton(tr("Reload from disk"), QMessageBox::DestructiveRole);
  reload->setObjectName("ReloadButton");
  QPushButton* save_as = box->addButton(tr("Save as…"), QMessageBox::AcceptRole);
  save_as->setObjectName("SaveAsButton");
  box->addButton(QMessageBox::Cancel);
  connect(box, &QMessageBox::buttonClicked, this, [this, box, reload, save_as, path](QAbstractButton* clicked) {
    if (clicked == reload) {
      OpenProject(path);  // the user chose to drop the unsaved changes
    } else if (clicked == save_as) {
      QTimer::singleShot(0, this, &MainWindow::SaveProjectAs);
    }
  });
  box->open();
}

bool MainWindow::MaybeSaveChanges() {
  if (!dirty()) return true;
  QMessageBox box(QMessageBox::Question, tr("Unsaved changes"),
                  tr("The changes to %1 have not been saved. Save them first?")
                      .arg(QString::fromStdString(project().file.filename().string())),
                  QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, this);
  box.setObjectName("UnsavedChangesDialog");
  const int answer = box.exec();
  if (answer == QMessageBox::Cancel) return false;
  if (answer == QMessageBox::Discard) return true;
  if (project().file.empty()) {
    SaveProjectAs();
    return !dirty();
  }
  return SaveProject(QString::fromStdString(project().file.string()));
}

bool MainWindow::NewProject(const QStringList& scan_files, const QString& project_path) {
  std::vector<std::filesystem::path> files;
  for (const QString& f : scan_files) files.push_back(f.toStdString());
  return jobs_->Start<AddedScans>(
      tr("Creating %1").arg(project_path),
      [files, path = project_path.toStdString(), cells = doc_->previewCells()](ProgressSink& progress,
                                                  const CancelToken& cancel) -> Expected<AddedScans> {
        pipeline::CreateProjectOptions options;
        options.scan_files = files;
        options.skip_unreadable = true;  // one bad file does not stop the others
        SubProgress create(progress, 0.0, 0.8);
        Expected<pipeline::CreatedProject> created = pipeline::CreateProject(path, options, create, cancel);
        if (!created) return created.error();
        SubProgress previews(progress, 0.8, 1.0);  // read back from the scan cache the creation filled
        Expected<LoadedProject> loaded = LoadJob(std::move(created->project), cells, previews, cancel);
        if (!loaded) return loaded.error();
        return AddedScans{std::move(loaded->project), std::move(loaded->previews), std::move(created->skipped)};
      },
      [this](AddedScans& created) {
        OnProjectLoaded(std::move(created.project), std::move(created.previews));
        ShowSkippedFiles(created.skipped);
      });
}

bool MainWindow::AddScans(const QStringList& scan_files) {
  if (project().file.empty()) {
    ShowError(tr("No project open"), tr("Create a project first (File → New project…), then add scans to it."));
    return false;
  }
  std::vector<std::filesystem::path> files;
  for (const QString& f : scan_files) files.push_back(f.toStdString());
  return jobs_->Start<AddedScans>(
      tr("Adding scans"),
      [files, project = project(), cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<AddedScans> {
        std::vector<std::string> skipped;
        const std::size_t before = project.scans.size();
        SubProgress append(progress, 0.0, 0.8);
        if (Status s = pipeline::AppendScanFiles(project, files, append, cancel, &skipped); !s) return s.error();
        std::vector<int> added;
        for (std::size_t i = before; i < project.scans.size(); ++i) added.push_back(static_cast<int>(i));
        std::vector<pipeline::ScanPreview> previews;
        if (!added.empty()) {
          SubProgress load(progress, 0.8, 1.0);  // read back from the scan cache the append filled
          Expected<std::vector<pipeline::ScanPreview>> p = pipeline::LoadScanPreviews(
              project, pipeline::PreviewCellsPerScan(project.scans.size(), cells), load, cancel, added);
          if (!p) return p.error();
          previews = std::move(*p);
        }
        return AddedScans{std::move(project), std::move(previews), std::move(skipped)};
      },
      [this](AddedScans& added) {
        if (!added.previews.empty()) doc_->AppendScans(std::move(added.project), std::move(added.previews));
        ShowSkippedFiles(added.skipped);
      });
}

void MainWindow::ShowSkippedFiles(const std::vector<std::string>& skipped) {
  if (skipped.empty()) return;
  QString list;
  for (const std::string& why : skipped) list += "• " + QString::fromStdString(why) + "\n";
  ShowError(tr("%n file(s) not added", "", int(skipped.size())),
            tr("The other files were added. These were left out:\n\n%1").arg(list));
}

bool MainWindow::ExportReport(const QString& dir) {
  if (project().scans.empty()) return false;
  return jobs_->Start<std::filesystem::path>(
      tr("Writing the report to %1").arg(dir),
      [project = project(), dir = dir.toStdString()](ProgressSink& progress, const CancelToken& cancel) {
        return report::WriteReport(project, dir, progress, cancel);
      },
      [](std::filesystem::path& index) { LogInfo("report written: " + index.string()); });
}

}  // namespace scanreg::ui
