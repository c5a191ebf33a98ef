#include "ui/screenshot_tour.h"

#include <QDir>
#include <QDockWidget>
#include <QHeaderView>
#include <QTableWidget>
#include <QTimer>

#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/merge_panel.h"
#include "ui/pair_inspector.h"
#include "ui/pick_points_dialog.h"
#include "ui/register_settings_dialog.h"
#include "ui/scan_scene.h"
#include "ui/view_3d.h"

namespace scanreg::ui {
namespace {

// Time for a floated dock to lay out and a VTK view to render before it is grabbed.
constexpr int kSettleMs = 400;

QImage GrabDock(MainWindow& window, const char* dock) {
  auto* d = window.findChild<QDockWidget*>(dock);
  return d ? d->widget()->grab().toImage() : QImage();
}

// A table grabbed only as far as its cells reach (not the empty space below and beside them).
QImage GrabTable(MainWindow& window, const char* dock) {
  auto* d = window.findChild<QDockWidget*>(dock);
  auto* table = d ? qobject_cast<QTableWidget*>(d->widget()) : nullptr;
  if (!table) return QImage();
  int w = table->verticalHeader()->width() + 2 * table->frameWidth() + 8;
  int h = table->horizontalHeader()->height() + 2 * table->frameWidth() + 8;
  for (int c = 0; c < table->columnCount(); ++c) w += table->columnWidth(c);
  for (int r = 0; r < table->rowCount(); ++r) h += table->rowHeight(r);
  return table->grab(QRect(0, 0, std::min(w, table->width()), std::min(h, table->height()))).toImage();
}

void ShowMeshOnly(MainWindow& w) {
  w.scene()->SetShowScans(false);
  w.scene()->SetShowMesh(true);
  w.view3d()->ResetCamera();  // frames the visible actors: the mesh
}

}  // namespace

std::vector<ScreenshotView> ScreenshotViews() {
  return {
      {"main_window.png", "", [](MainWindow& w) { w.scene()->SetShowMesh(false); },
       [](MainWindow& w) { return w.Screenshot(); }},
      {"view_3d_scans.png", "", [](MainWindow& w) { w.scene()->SetShowMesh(false); },
       [](MainWindow& w) { return w.view3d()->GrabImage(); }},
      {"scan_network.png", "ScanNetworkDock", {}, [](MainWindow& w) { return GrabDock(w, "ScanNetworkDock"); }},
      {"confusion_matrix.png",
       "ConfusionMatrixDock",
       {},
       [](MainWindow& w) { return GrabTable(w, "ConfusionMatrixDock"); }},
      {"merge_preview.png", "", ShowMeshOnly, [](MainWindow& w) { return w.view3d()->GrabImage(); }},
      {"merge_panel.png", "",
       [](MainWindow& w) {
         ShowMeshOnly(w);
         if (auto* dock = w.findChild<QDockWidget*>("MergePanelDock")) dock->raise();
       },
       [](MainWindow& w) { return w.Screenshot(); }},
      {"register_settings.png", "", [](MainWindow& w) { w.EditRegisterSettings(); },
       [](MainWindow& w) {
         auto* dialog = w.findChild<RegisterSettingsDialog*>();
         if (!dialog) return QImage();
         const QImage image = dialog->grab().toImage();
         dialog->close();
         return image;
       }},
      {"pick_points.png", "",
       [](MainWindow& w) {
         const std::vector<io::ProjectScan>& scans = w.project().scans;
         if (scans.size() >= 2) w.PickPoints(QString::fromStdString(scans.back().name));
       },
       [](MainWindow& w) {
         auto* dialog = w.findChild<PickPointsDialog*>();
         if (!dialog) return QImage();
         const QImage image = dialog->grab().toImage();
         dialog->close();
         return image;
       }},
      // The pair view replaces the 3D view's scene: keep it last.
      {"pair_view.png", "",
       [](MainWindow& w) {
         const std::vector<io::ProjectScan>& scans = w.project().scans;
         if (scans.size() >= 3 &&
             w.pairInspector()->OpenPair(QString::fromStdString(scans[1].name), QString::fromStdString(scans[2].name)))
           w.pairInspector()->RunPair();
       },
       [](MainWindow& w) { return w.Screenshot(); }},
  };
}

merge::MergeOptions ScreenshotTour::DemoMerge() {
  merge::MergeOptions options;
  options.method = merge::MergeMethod::kTsdf;
  options.voxel_m = 0.1;
  options.max_range_m = 25.0;
  return options;
}

ScreenshotTour::ScreenshotTour(MainWindow* window, QString dir, merge::MergeOptions merge)
    : QObject(window), window_(window), dir_(std::move(dir)), merge_(merge), views_(ScreenshotViews()) {
  connect(window_->jobs(), &JobRunner::Succeeded, this,
          [this](const QString& title) { OnJobDone(title, true, QString()); });
  connect(window_->jobs(), &JobRunner::Failed, this,
          [this](const QString& title, const QString& message, bool) { OnJobDone(title, false, message); });
}

bool ScreenshotTour::Prepare() {
  stage_ = Stage::kLoading;
  if (!QDir().mkpath(dir_)) {
    stage_ = Stage::kDone;
    emit Finished(false, tr("cannot create the folder '%1'; choose a writable one").arg(dir_));
    return false;
  }
  return true;
}

void ScreenshotTour::StartDemo(const QString& demo_dir) {
  if (Prepare() && !window_->OpenDemoProject(demo_dir)) emit Finished(false, tr("another job is running"));
}

void ScreenshotTour::Start(const QString& project) {
  if (Prepare() && !window_->OpenProject(project)) emit Finished(false, tr("cannot open '%1'").arg(project));
}

void ScreenshotTour::OnJobDone(const QString& title, bool ok, const QString& message) {
  if (stage_ == Stage::kDone || stage_ == Stage::kShooting) return;
  qInfo("screenshots: %s: %s", qPrintable(title), ok ? "done" : "failed");
  if (!ok) {
    stage_ = Stage::kDone;
    emit Finished(false, title + ": " + message);
    return;
  }
  // Queued: the window and the panels finish handling this job's result first.
  QTimer::singleShot(0, this, [this] {
    bool registered = false;
    for (const io::ProjectScan& s : window_->project().scans) registered |= s.registered;
    if (stage_ == Stage::kLoading && !registered) {
      stage_ = Stage::kRegistering;
      window_->RegisterProject();
    } else if (stage_ == Stage::kLoading || stage_ == Stage::kRegistering) {
      window_->mergePanel()->SetOptions(merge_);
      stage_ = Stage::kMerging;
      if (!window_->mergePanel()->Run()) {
        stage_ = Stage::kDone;
        emit Finished(false, tr("nothing to merge: no scan was registered"));
      }
    } else if (stage_ == Stage::kMerging) {
      stage_ = Stage::kShooting;
      // Room for the scan list's columns.
      if (auto* dock = window_->findChild<QDockWidget*>("ScanListDock"))
        window_->resizeDocks({dock}, {kRightDockWidth}, Qt::Horizontal);
      ShootNext();
    }
  });
}

void ScreenshotTour::ShootNext() {
  if (next_ >= views_.size()) {
    stage_ = Stage::kDone;
    emit Finished(true, tr("wrote %1").arg(written_.join(", ")));
    return;
  }
  const ScreenshotView& view = views_[next_];
  QDockWidget* dock = view.dock.isEmpty() ? nullptr : window_->findChild<QDockWidget*>(view.dock);
  if (dock) {
    dock->setFloating(true);
    dock->resize(kPanelWidth, kPanelHeight);
    dock->show();
  }
  if (view.prepare) view.prepare(*window_);
  Grab(dock, 0);
}

void ScreenshotTour::Grab(QDockWidget* dock, int idle_checks) {
  QTimer::singleShot(kSettleMs, this, [this, dock, idle_checks] {
    // A view whose preparation started jobs (a pair registration) is grabbed once the worker has
    // been idle for two checks in a row (a queued job may start right after another).
    if (window_->jobs()->busy() || idle_checks < 1) {
      Grab(dock, window_->jobs()->busy() ? 0 : idle_checks + 1);
      return;
    }
    const ScreenshotView& view = views_[next_];
    const QImage image = view.grab(*window_);
    if (dock) dock->setFloating(false);
    const QString path = QDir(dir_).filePath(view.file);
    if (image.isNull() || !image.save(path)) {
      stage_ = Stage::kDone;
      emit Finished(false, tr("could not grab or write '%1'").arg(path));
      return;
    }
    qInfo("screenshots: wrote %s", qPrintable(path));
    written_ << path;
    ++next_;
    ShootNext();
  });
}

}  // namespace scanreg::ui
