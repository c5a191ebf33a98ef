// Drives the real main window under Xvfb: menus, the 3D view, the demo project loaded and
// registered on the worker thread, cancel, save.
#include <QVTKOpenGLNativeWidget.h>
#include <QComboBox>
#include <QDockWidget>
#include <QDoubleSpinBox>
#include <QElapsedTimer>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QPushButton>
#include <QSignalSpy>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QtTest/QtTest>

#include "core/io/project.h"
#include "core/io/project_lock.h"
#include "core/io/project_tree.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/register_settings.h"
#include "tests/ui/wait_for_job.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/network_panel.h"
#include "ui/pose_dialog.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"
#include "ui/register_settings_dialog.h"
#include "ui/scan_scene.h"
#include "ui/view_3d.h"

using scanreg::test::WaitForJob;
using scanreg::ui::JobRunner;
using scanreg::ui::MainWindow;

// A tiny simulated project (2 stations of 200 x 50) written into dir/p.
scanreg::Expected<scanreg::io::Project> WriteTinyProject(const QTemporaryDir& dir) {
  scanreg::SimulatedProjectOptions sim;
  sim.stations = 2;
  sim.scanner.cols = 200;
  sim.scanner.rows = 50;
  scanreg::NullProgress progress;
  return scanreg::pipeline::WriteSimulatedProject(sim, dir.filePath("p").toStdString(), progress,
                                                  scanreg::CancelToken());
}

class MainWindowTest : public QObject {
  Q_OBJECT

 private slots:
  void HasMenusAndAnEmpty3dView() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QStringList menus;
    for (QAction* a : window.menuBar()->actions()) menus << a->text().remove('&');
    QCOMPARE(menus, QStringList({"File", "Edit", "Registration", "View", "Help"}));
    QCOMPARE(window.view3d()->PropCount(), 0);
    QVERIFY(!window.RegisterProject());  // nothing to register without a project
  }

  void ScreenshotShowsTheRenderedView() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTest::qWait(200);
    QTemporaryDir dir;
    const QString path = dir.filePath("shot.png");
    QVERIFY(window.SaveScreenshot(path));
    QImage image(path);
    QVERIFY(!image.isNull());
    // The 3D view's background is a dark gradient, not the widget's default grey: sample its centre.
    const QPoint centre = window.view3d()->mapTo(&window, window.view3d()->rect().center());
    const QColor c = image.pixelColor(centre);
    QVERIFY2(c.red() < 120 && c.blue() > c.red(), qPrintable(QString("centre colour %1").arg(c.name())));
  }

  void BadProjectFileShowsADialogNamingIt() {
    MainWindow window;
    window.show();
    QTemporaryDir dir;
    const QString path = dir.filePath("broken.scanreg.json");
    QFile f(path);
    QVERIFY(f.open(QIODevice::WriteOnly));
    f.write("{ not json");
    f.close();
    QVERIFY(!window.OpenProject(path));
    auto* box = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(box != nullptr);
    QVERIFY2(box->text().contains("broken.scanreg.json"), qPrintable(box->text()));
  }

  // The project's saved registration settings are what a re-run from the GUI uses; the settings
  // dialog shows them and stores an edit in the project (undoable).
  void RegistrationUsesAndEditsTheProjectsSavedSettings() {
    QTemporaryDir dir;
    auto project = WriteTinyProject(dir);
    QVERIFY(project.ok());
    scanreg::pipeline::RegisterOptions saved;
    saved.from_current_poses = true;
    saved.fine = scanreg::pipeline::FineMethod::kEm;
    saved.range_sigma_m = 0.0005;
    saved.overlap_distance_m = 0.01;
    scanreg::pipeline::StoreRegisterSettings(saved, &project->settings);
    QVERIFY(scanreg::io::SaveProject(*project, project->file).ok());
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(project->file.string())));
    QVERIFY(WaitForJob(window, 120000));
    const scanreg::pipeline::RegisterOptions used = window.RegistrationOptions();
    QVERIFY(used.from_current_poses);
    QVERIFY(used.fine == scanreg::pipeline::FineMethod::kEm);
    QCOMPARE(used.range_sigma_m, 0.0005);
    QCOMPARE(used.overlap_distance_m, 0.01);

    scanreg::ui::RegisterSettingsDialog* dialog = window.EditRegisterSettings();
    QVERIFY(dialog != nullptr);
    const auto& settings = scanreg::pipeline::RegisterSettings();
    int fine = -1, noise = -1;
    for (std::size_t i = 0; i < settings.size(); ++i) {
      if (std::string(settings[i].key) == "register.fine") fine = int(i);
      if (std::string(settings[i].key) == "register.noise_m") noise = int(i);
    }
    auto* fine_box = qobject_cast<QComboBox*>(dialog->field(fine));
    auto* noise_edit = qobject_cast<QLineEdit*>(dialog->field(noise));
    QVERIFY(fine_box && noise_edit);
    QCOMPARE(fine_box->currentText(), QString("em"));
    QCOMPARE(noise_edit->text().toDouble(), 0.0005);
    noise_edit->setText("lots");  // refused with the setting named; the dialog stays open
    dialog->accept();
    QVERIFY(dialog->isVisible());
    QCOMPARE(std::stod(window.project().settings.at("register.noise_m")), 0.0005);
    fine_box->setCurrentText("projective-icp");
    noise_edit->setText("0.002");
    dialog->accept();
    QCOMPARE(window.project().settings.at("register.fine"), std::string("projective-icp"));
    QCOMPARE(window.RegistrationOptions().range_sigma_m, 0.002);
    QVERIFY(window.dirty());
    window.undoStack()->undo();
    QCOMPARE(window.project().settings.at("register.fine"), std::string("em"));
  }

  void FitsA1366By768LaptopWithEveryViewShown() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTemporaryDir dir;
    QVERIFY(window.OpenDemoProject(dir.filePath("demo")));
    QVERIFY(WaitForJob(window, 300000));
    window.resize(1366, 768);
    QTest::qWait(200);
    const QSize hint = window.minimumSizeHint();
    QVERIFY2(window.width() <= 1366 && window.height() <= 768,
             qPrintable(QString("window %1 x %2 (minimum %3 x %4)")
                            .arg(window.width())
                            .arg(window.height())
                            .arg(hint.width())
                            .arg(hint.height())));
    QVERIFY2(window.view3d()->width() >= 300 && window.view3d()->height() >= 200,
             qPrintable(QString("3D view %1 x %2").arg(window.view3d()->width()).arg(window.view3d()->height())));
    for (QDockWidget* dock : window.findChildren<QDockWidget*>()) {
      if (dock->isHidden() || window.tabifiedDockWidgets(dock).contains(dock)) continue;
      if (!dock->visibleRegion().isEmpty())
        QVERIFY2(dock->width() > 50 && dock->height() > 50, qPrintable(dock->objectName()));
    }
  }

  void EscapeCancelsTheRunningJob() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTemporaryDir dir;
    window.activateWindow();
    QVERIFY(QTest::qWaitForWindowActive(&window));
    QVERIFY(window.OpenDemoProject(dir.filePath("demo")));
    QVERIFY(window.jobs()->busy());
    QTest::keyClick(&window, Qt::Key_Escape);
    bool cancelled = false;
    QVERIFY(!WaitForJob(window, 300000, &cancelled));
    QVERIFY(cancelled);
    QVERIFY(window.project().scans.empty());  // nothing half-loaded
  }

  void SaveRefusesALockedOrChangedProjectAndOffersReload() {
    QTemporaryDir dir;
    const auto simulated = WriteTinyProject(dir);
    QVERIFY(simulated.ok());
    const QString path = QString::fromStdString(simulated->file.string());
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(path));
    QVERIFY(WaitForJob(window, 120000));

    {  // another run (here: this process, as `scanreg-cli register` would) holds the project's lock
      auto lock = scanreg::io::ProjectLock::Acquire(simulated->file, "scanreg-cli register");
      QVERIFY(lock.ok());
      QVERIFY(!window.SaveProject(path));
      auto* box = window.findChild<QMessageBox*>("ErrorDialog");
      QVERIFY(box != nullptr);
      QVERIFY2(box->text().contains("being written by another run"), qPrintable(box->text()));
      box->close();
      QTest::qWait(50);
    }

    // Another program changes the project on disk; the GUI's save does not overwrite it.
    auto disk = scanreg::io::LoadProject(simulated->file);
    QVERIFY(disk.ok());
    disk->settings["noise"] = "0.02";
    QVERIFY(scanreg::io::SaveProject(*disk, simulated->file).ok());
    const QByteArray before = [&] { QFile f(path); f.open(QIODevice::ReadOnly); return f.readAll(); }();
    QVERIFY(!window.SaveProject(path));
    const QByteArray after = [&] { QFile f(path); f.open(QIODevice::ReadOnly); return f.readAll(); }();
    QCOMPARE(after, before);
    auto* conflict = window.findChild<QMessageBox*>("ConflictDialog");
    QVERIFY(conflict != nullptr);
    auto* reload = conflict->findChild<QPushButton*>("ReloadButton");
    QVERIFY(reload != nullptr);
    reload->click();
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(QString::fromStdString(window.project().settings.at("noise")), QString("0.02"));
    QVERIFY(!window.dirty());
    QVERIFY(window.SaveProject(path));  // what was reloaded saves again
  }

  // Issue 13: the window keeps previews of the scans (within a global cell budget), shows the full
  // scans' grids and counts, and registers from the full scans read from their files — the same
  // poses as the core registration of the full scans.
  void ALargeProjectIsDrawnFromPreviewsAndRegisteredFromItsFiles() {
    QTemporaryDir dir;
    scanreg::SimulatedProjectOptions sim;
    sim.stations = 3;
    sim.scanner.cols = 600;
    sim.scanner.rows = 150;
    scanreg::NullProgress progress;
    const scanreg::Expected<scanreg::io::Project> written = scanreg::pipeline::WriteSimulatedProject(
        sim, dir.filePath("p").toStdString(), progress, scanreg::CancelToken());
    QVERIFY(written.ok());
    const scanreg::Expected<std::vector<scanreg::Scan>> full =
        scanreg::pipeline::LoadProjectScans(*written, progress, scanreg::CancelToken());
    QVERIFY(full.ok());

    MainWindow window;
    window.show();
    window.document()->SetPreviewCells(60'000);  // 20 000 a scan: every third row and column
    QVERIFY(window.OpenProject(QString::fromStdString(written->file.string())));
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(static_cast<int>(window.previews().size()), 3);
    for (int i = 0; i < 3; ++i) {
      const scanreg::pipeline::ScanPreview& p = window.previews()[i];
      QCOMPARE(p.stride, 3);
      QVERIFY(p.scan.size() <= 20'000u);
      QCOMPARE(window.scanList()->item(i, 1)->text(), QString("600 × 150"));
      QCOMPARE(window.scanList()->item(i, 2)->text(), QString::number((*full)[i].CountValid()));
    }
    window.scene()->SetFullResolution(true);  // every point of the previews, never the full scans
    std::size_t preview_points = 0;
    for (const auto& p : window.previews()) preview_points += p.scan.CountValid();
    QCOMPARE(window.scene()->DrawnPoints(), preview_points);

    scanreg::io::Project expected = window.project();
    const scanreg::Expected<scanreg::pipeline::ProjectRegistration> core = scanreg::pipeline::RegisterProjectScans(
        expected, *full, window.RegistrationOptions(), progress, scanreg::CancelToken());
    QVERIFY(core.ok());
    QVERIFY(window.RegisterProject());
    QVERIFY(WaitForJob(window, 300000));
    int registered = 0;
    for (int i = 0; i < 3; ++i) {
      const scanreg::io::ProjectScan &got = window.project().scans[i], &want = expected.scans[i];
      QCOMPARE(got.registered, want.registered);
      registered += got.registered;
      QVERIFY2(got.world_from_scan.isApprox(want.world_from_scan, 1e-9), got.name.c_str());
    }
    QCOMPARE(registered, 3);
  }

  void DemoProjectLoadsRegistersCancelsAndSaves() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTemporaryDir dir;
    QVERIFY(window.OpenDemoProject(dir.filePath("demo")));
    QVERIFY(!window.OpenDemoProject(dir.filePath("other")));  // one job at a time
    QVERIFY(WaitForJob(window, 300000));
    QCOMPARE(static_cast<int>(window.previews().size()), 5);
    QCOMPARE(window.scanList()->rowCount(), 5);
    QVERIFY(window.view3d()->PropCount() > 0);

    // Cancel a registration right away: the project is unchanged.
    std::vector<Eigen::Matrix4d> before;
    for (const auto& s : window.project().scans) before.push_back(s.world_from_scan.matrix());
    QVERIFY(window.RegisterProject());
    window.jobs()->Cancel();
    bool cancelled = false;
    QVERIFY(!WaitForJob(window, 300000, &cancelled));
    QVERIFY(cancelled);
    for (std::size_t i = 0; i < before.size(); ++i) {
      QVERIFY(window.project().scans[i].world_from_scan.matrix() == before[i]);
      QVERIFY(!window.project().scans[i].registered);
    }

    // Register for real: the panels fill, most scans are registered, the project is dirty.
    QVERIFY(window.RegisterProject());
    QVERIFY(WaitForJob(window, 600000));
    QCOMPARE(static_cast<int>(window.confusion().rows()), 5);
    QCOMPARE(window.confusionPanel()->rowCount(), 5);
    QVERIFY(window.confusion()(0, 0) > 100);  // the diagonal holds the feature counts
    int registered = 0;
    for (int r = 0; r < window.scanList()->rowCount(); ++r)
      registered += window.scanList()->item(r, 3)->text() == "registered";
    QVERIFY2(registered >= 4, qPrintable(QString("%1 registered").arg(registered)));
    QVERIFY(window.dirty());

    QCOMPARE(window.networkPanel()->NodeCount(), 5);
    QVERIFY(window.networkPanel()->EdgeCount() >= registered - 1);

    // Override s05's parent: registered on the worker (s05 and the scans under it only); undoable
    // when the link holds, and when it fails s05 keeps its old link and a dialog says so.
    const std::string old_parent = [&] {
      for (const auto& l : window.project().links)
        if (l.child == "s05" && !l.loop_check && l.status != scanreg::io::LinkStatus::kFailed) return l.parent;
      return std::string();
    }();
    const QString new_parent = old_parent == "s03" ? "s02" : "s03";
    const Eigen::Matrix4d pose_before = window.project().scans[4].world_from_scan.matrix();
    const bool registered_before = window.project().scans[4].registered;
    const int undo_before = window.undoStack()->count();
    QVERIFY(window.SetParentOverride("s05", new_parent));
    QVERIFY(window.jobs()->busy());
    QVERIFY(WaitForJob(window, 600000));
    const scanreg::io::LinkRecord* now = nullptr;
    for (const auto& l : window.project().links)
      if (l.child == "s05" && scanreg::io::IsTreeLink(l)) now = &l;
    if (window.project().scans[4].parent_override) {
      QCOMPARE(QString::fromStdString(*window.project().scans[4].parent_override), new_parent);
      QVERIFY(now == nullptr || now->parent == new_parent.toStdString());
      QCOMPARE(window.undoStack()->count(), undo_before + 1);
      window.undoStack()->undo();
    } else {  // the forced link failed: nothing changed but the dialog
      QVERIFY(registered_before);
      QVERIFY(window.findChild<QMessageBox*>("ErrorDialog") != nullptr);
      QCOMPARE(window.undoStack()->count(), undo_before);
    }
    QVERIFY(!window.project().scans[4].parent_override.has_value());
    // Undo restores the registration as it was before the override.
    QCOMPARE(window.project().scans[4].registered, registered_before);
    QVERIFY(window.project().scans[4].world_from_scan.matrix() == pose_before);

    // The confusion matrix is shown in scan order: the root first, then as the scans were placed.
    const std::vector<int> order = scanreg::io::OrderedScanIndices(window.project());
    QCOMPARE(window.confusionPanel()->horizontalHeaderItem(0)->text(), QString::fromStdString(*window.project().root));
    for (int i = 0; i < 5; ++i)
      QCOMPARE(window.confusionPanel()->item(i, 0)->text().toInt(), window.confusion()(order[i], order[0]));

    // Place s05 by hand through the dialog: moved by 1 m in x, marked manual; undo restores it.
    const Eigen::Isometry3d s05_before = window.project().scans[4].world_from_scan;
    window.scanList()->setCurrentCell(4, 0);
    scanreg::ui::PoseDialog* dialog = window.EditSelectedScanPose();
    QVERIFY(dialog != nullptr);
    QCOMPARE(dialog->field(0)->value(), std::round(s05_before.translation().x() * 1e4) / 1e4);
    dialog->field(0)->setValue(dialog->field(0)->value() + 1.0);
    dialog->accept();
    const Eigen::Isometry3d s05_after = window.project().scans[4].world_from_scan;
    QVERIFY(std::abs(s05_after.translation().x() - s05_before.translation().x() - 1.0) < 1e-3);
    QVERIFY(s05_after.linear().isApprox(s05_before.linear(), 1e-5));  // angles shown to 1e-4 degree
    QVERIFY(window.project().scans[4].manual_pose);
    QCOMPARE(window.scanList()->item(4, 3)->text(), QString("manual pose"));
    window.undoStack()->undo();
    QVERIFY(window.project().scans[4].world_from_scan.matrix() == s05_before.matrix());
    QVERIFY(!window.project().scans[4].manual_pose);
    if (window.jobs()->busy()) QVERIFY(WaitForJob(window, 300000));  // a panorama the selection may have started

    // Save and re-read: the registration is in the file.
    const QString path = dir.filePath("saved.scanreg.json");
    QVERIFY(window.SaveProject(path));
    QVERIFY(!window.dirty());
    auto saved = scanreg::io::LoadProject(path.toStdString());
    QVERIFY(saved.ok());
    int saved_registered = 0;
    for (const auto& s : saved->scans) saved_registered += s.registered;
    int shown_registered = 0;
    for (const auto& s : window.project().scans) shown_registered += s.registered;
    QCOMPARE(saved_registered, shown_registered);
    QVERIFY(!saved->scans[4].parent_override.has_value());
  }
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  MainWindowTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "main_window_test.moc"
