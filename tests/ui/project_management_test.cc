// Issue 14, item 6 on the real window: batch add that adds every readable file and lists the
// others; rename, remove (undoable, points kept), set the root; scan files moved to another folder
// and found again on open; round trip through save and reopen.
#include <QMessageBox>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QtTest/QtTest>
#include <filesystem>
#include <fstream>

#include "core/io/project.h"
#include "core/pipeline/create_project.h"
#include "tests/ui/wait_for_job.h"
#include "ui/main_window.h"

using scanreg::test::WaitForJob;
using scanreg::ui::MainWindow;
namespace fs = std::filesystem;

class ProjectManagementTest : public QObject {
  Q_OBJECT

 private slots:
  void AddRenameRemoveMoveAndReopen() {
    QTemporaryDir dir;
    scanreg::SimulatedProjectOptions sim;
    sim.stations = 2;
    sim.scanner.cols = 200;
    sim.scanner.rows = 50;
    scanreg::NullProgress progress;
    const fs::path first = dir.filePath("A").toStdString();
    auto written = scanreg::pipeline::WriteSimulatedProject(sim, first, progress, scanreg::CancelToken());
    QVERIFY(written.ok());
    // A third station's file (a copy under another name) and a file that is not a scan.
    fs::copy_file(written->scans[1].path, first / "extra.ptx");
    std::ofstream(first / "garbage.ptx") << "200\n50\nnot a number\n";

    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(written->file.string())));
    QVERIFY(WaitForJob(window, 120000));
    QVERIFY(window.AddScans({QString::fromStdString((first / "garbage.ptx").string()),
                             QString::fromStdString((first / "extra.ptx").string()),
                             QString::fromStdString(written->scans[0].path.string())}));
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(static_cast<int>(window.project().scans.size()), 3);
    QCOMPARE(static_cast<int>(window.previews().size()), 3);
    QCOMPARE(QString::fromStdString(window.project().scans[2].name), QString("extra"));
    auto* box = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(box != nullptr);
    QVERIFY2(box->text().contains("garbage.ptx") && box->text().contains("already in the project"),
             qPrintable(box->text()));
    box->close();

    // Rename, remove, root: each undoable; the removed scan's points come back with undo.
    QVERIFY(window.RenameScan("s02", "north"));
    QVERIFY(!window.RenameScan("s01", "north"));  // names stay unique (a dialog says so)
    QCOMPARE(QString::fromStdString(window.previews()[1].scan.name), QString("north"));
    QVERIFY(window.RemoveScan("extra"));
    QCOMPARE(static_cast<int>(window.previews().size()), 2);
    window.undoStack()->undo();
    QCOMPARE(static_cast<int>(window.previews().size()), 3);
    QCOMPARE(window.previews()[2].full_valid, window.previews()[1].full_valid);
    window.undoStack()->redo();
    QCOMPARE(static_cast<int>(window.project().scans.size()), 2);
    QVERIFY(window.SetRoot("north"));
    QCOMPARE(QString::fromStdString(window.project().root.value_or("")), QString("north"));
    QVERIFY(window.SaveProject(QString::fromStdString(written->file.string())));

    // The scan files move: the project asks for their folder, then opens relinked and unsaved.
    const fs::path second = dir.filePath("B").toStdString();
    fs::create_directories(second);
    for (const char* f : {"s01.ptx", "s02.ptx", "extra.ptx"}) fs::rename(first / f, second / f);
    const QString path = QString::fromStdString(written->file.string());
    QVERIFY(!window.OpenProject(path));
    QVERIFY(window.findChild<QMessageBox*>("MissingFilesDialog") != nullptr);
    QVERIFY(window.OpenProject(path, QString::fromStdString(second.string())));
    QVERIFY(WaitForJob(window, 120000));
    QVERIFY(window.dirty());
    QCOMPARE(static_cast<int>(window.previews().size()), 2);
    QVERIFY(window.SaveProject(path));

    auto reopened = scanreg::io::LoadProject(path.toStdString());
    QVERIFY(reopened.ok());
    QCOMPARE(static_cast<int>(reopened->scans.size()), 2);
    QCOMPARE(QString::fromStdString(reopened->scans[1].name), QString("north"));
    QCOMPARE(QString::fromStdString(reopened->root.value_or("")), QString("north"));
    QVERIFY(reopened->scans[1].path == fs::absolute(second / "s02.ptx").lexically_normal());

    // Relinking a scan to a file of another grid is refused on the worker, with a dialog.
    scanreg::SimulatedProjectOptions other = sim;
    other.scanner.cols = 100;
    auto small = scanreg::pipeline::WriteSimulatedProject(other, dir.filePath("C").toStdString(), progress,
                                                          scanreg::CancelToken());
    QVERIFY(small.ok());
    QVERIFY(window.RelinkScan("s01", QString::fromStdString(small->scans[0].path.string())));
    QVERIFY(!WaitForJob(window, 120000));
    QVERIFY(window.project().scans[0].path == fs::absolute(second / "s01.ptx").lexically_normal());
  }
};

QTEST_MAIN(ProjectManagementTest)
#include "project_management_test.moc"
