// The georeferencing parts of the main window (issue 15): importing control points, picking
// targets in a scan's panorama, and placing the registered project on control without
// registering it again.
#include <QApplication>
#include <QStatusBar>

#include "core/common/log.h"
#include "core/pipeline/georeference_project.h"
#include "core/pipeline/project_edits.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/pick_target_dialog.h"
#include "ui/project_document.h"

namespace scanreg::ui {

bool MainWindow::ImportControl(const QString& path) {
  io::Project after = project();
  if (Status s = pipeline::ImportControl(path.toStdString(), {}, after); !s) {
    ShowError(tr("Import control points"), QString::fromStdString(s.error().message));
    return false;
  }
  const int n = static_cast<int>(after.control.size());
  doc_->Edit(tr("import %1 control points").arg(n), std::move(after));
  statusBar()->showMessage(tr("%1 control points imported: register (Ctrl+R) to place the project on them").arg(n),
                           12000);
  return true;
}

PickTargetDialog* MainWindow::PickTarget(const QString& scan) {
  const int i = project().FindScan(scan.toStdString());
  if (i < 0) {
    ShowError(tr("Pick a target"), tr("Select a scan in the scan list first."));
    return nullptr;
  }
  QApplication::setOverrideCursor(Qt::WaitCursor);
  Expected<Scan> full = doc_->ReadScan(i);  // targets are picked on the full scan
  QApplication::restoreOverrideCursor();
  if (!full) {
    ShowError(tr("Pick a target"), QString::fromStdString(full.error().message));
    return nullptr;
  }
  QStringList names;
  for (const io::ControlPoint& c : project().control) names << QString::fromStdString(c.name);
  const pipeline::RegisterOptions options = RegistrationOptions();
  georef::CheckerTargetOptions checkers = options.checkers;
  if (checkers.size_m == 0) checkers.size_m = georef::CheckerTargetOptions().size_m;  // a pick may still be a board
  auto* dialog = new PickTargetDialog(*full, names, options.spheres, checkers, this);
  dialog->setAttribute(Qt::WA_DeleteOnClose);
  connect(dialog, &QDialog::accepted, this, [this, dialog] {
    if (auto t = dialog->Target()) AddPickedTarget(*t);
  });
  dialog->open();
  return dialog;
}

bool MainWindow::AddPickedTarget(const io::TargetRecord& target) {
  io::Project after = project();
  if (Status s = pipeline::AddPickedTarget(after, target); !s) {
    ShowError(tr("Pick a target"), QString::fromStdString(s.error().message));
    return false;
  }
  const QString name = target.name.empty() ? tr("an unnamed target") : QString::fromStdString(target.name);
  doc_->Edit(tr("pick %1 in %2").arg(name, QString::fromStdString(target.scan)), std::move(after));
  statusBar()->showMessage(tr("Picked %1 in %2: Registration → Georeference on control uses it")
                               .arg(name, QString::fromStdString(target.scan)),
                           12000);
  return true;
}

bool MainWindow::Georeference() {
  if (project().control.empty()) {
    ShowError(tr("Georeference"), tr("The project has no control points: File → Import control points… first."));
    return false;
  }
  return jobs_->Start<io::Project>(
      tr("Georeferencing"),
      [project = project(), scans = doc_->FullScans(), options = RegistrationOptions()](
          ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<io::Project> {
        auto placed = pipeline::GeoreferenceProject(project, *scans, options, progress, cancel);
        if (!placed) return placed.error();
        return project;
      },
      [this](io::Project& placed) {
        const QString summary = tr("georeferenced on %1 control points, RMS %2 mm")
                                    .arg(placed.georef ? placed.georef->used : 0)
                                    .arg(placed.georef ? placed.georef->rms_m * 1000 : 0.0, 0, 'f', 1);
        doc_->Edit(tr("georeference"), std::move(placed));
        statusBar()->showMessage(summary, 12000);
        LogInfo(summary.toStdString());
      });
}

}  // namespace scanreg::ui
