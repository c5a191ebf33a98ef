// Issue 15 in the window: the Control dock shows the last adjustment's residuals graded against
// the tolerance; File → Import control points replaces the project's control as an undoable edit
// and says when the file is bad.
#include <QMessageBox>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QtTest/QtTest>
#include <filesystem>
#include <fstream>

#include "core/io/project.h"
#include "core/pipeline/create_project.h"
#include "tests/ui/wait_for_job.h"
#include <vtkActor.h>
#include <vtkMapper.h>
#include <vtkPolyData.h>

#include "ui/control_panel.h"
#include "ui/main_window.h"
#include "ui/scan_cloud_actors.h"

using scanreg::test::WaitForJob;
using scanreg::ui::MainWindow;
namespace fs = std::filesystem;

class ControlPanelTest : public QObject {
  Q_OBJECT

 private slots:
  void ShowsGradedResidualsAndImportsControl() {
    QTemporaryDir dir;
    scanreg::SimulatedProjectOptions sim;
    sim.stations = 2;
    sim.scanner.cols = 200;
    sim.scanner.rows = 50;
    scanreg::NullProgress progress;
    auto written = scanreg::pipeline::WriteSimulatedProject(sim, dir.filePath("p").toStdString(), progress,
                                                           scanreg::CancelToken());
    QVERIFY(written.ok());
    // A project placed on 3 control points, one of them left out as a blunder (5 cm, red).
    scanreg::io::Project p = *written;
    for (const char* name : {"CP1", "CP2", "CP3", "CP4"}) {
      scanreg::io::ControlPoint c;
      c.name = name;
      c.position = Eigen::Vector3d(512000.0 + p.control.size(), 5400000.0, 100.0);
      p.control.push_back(c);
    }
    scanreg::io::GeorefRecord g;
    g.rms_m = 0.0021;
    g.used = 3;
    g.targets = 4;
    g.tolerance_m = 0.01;
    const double deltas[4] = {0.001, 0.004, 0.05, 0.006};
    const char* roles[4] = {"used", "used", "blunder", "used"};
    for (int k = 0; k < 4; ++k) {
      scanreg::io::ControlResidualRecord r;
      r.name = p.control[k].name;
      r.role = roles[k];
      r.delta = Eigen::Vector3d(deltas[k], 0, 0);
      r.observations = 2;
      g.control.push_back(r);
    }
    p.georef = g;
    // Two target observations of the first scan, one far off after the adjustment.
    for (int k = 0; k < 2; ++k) {
      scanreg::io::TargetRecord t;
      t.scan = p.scans[0].name;
      t.name = p.control[k].name;
      t.center = Eigen::Vector3d(3.0 + k, -1.0, 0.2);
      t.residual_m = k == 0 ? 0.001 : 0.05;
      p.targets.push_back(t);
    }
    QVERIFY(scanreg::io::SaveProject(p, p.file).ok());

    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(p.file.string())));
    QVERIFY(WaitForJob(window, 120000));
    auto* panel = window.findChild<scanreg::ui::ControlPanel*>("ControlPanel");
    QVERIFY(panel != nullptr);
    QTableWidget* table = panel->table();
    QCOMPARE(table->rowCount(), 4);
    QVERIFY2(panel->summary().contains("2.1 mm"), qPrintable(panel->summary()));
    QCOMPARE(table->item(2, 1)->text(), QString("blunder"));
    QCOMPARE(table->item(2, 8)->text(), QString("red"));
    QCOMPARE(table->item(0, 8)->text(), QString("green"));
    QCOMPARE(table->item(3, 8)->text(), QString("orange"));
    QVERIFY(table->item(2, 0)->background().color() != table->item(0, 0)->background().color());

    // The 3D view draws the targets where their scan's pose puts them (relative to the scene origin).
    scanreg::io::Project drawn = window.project();
    for (auto& s : drawn.scans) s.registered = true;
    const scanreg::ui::ScanActors actors =
        scanreg::ui::MakeScanActors(window.scans(), drawn, scanreg::ui::CloudColouring::kPerScan, 1000);
    QVERIFY(actors.targets != nullptr);
    auto* poly = vtkPolyData::SafeDownCast(actors.targets->GetMapper()->GetInput());
    QVERIFY(poly != nullptr);
    QCOMPARE(static_cast<int>(poly->GetNumberOfPoints()), 2);
    const Eigen::Vector3d expect = drawn.scans[0].world_from_scan * Eigen::Vector3d(4.0, -1.0, 0.2) -
                                   scanreg::ui::SceneOrigin(drawn);
    double at[3];
    poly->GetPoint(1, at);
    QVERIFY((Eigen::Vector3d(at[0], at[1], at[2]) - expect).norm() < 1e-4);

    // A bad control file: a dialog naming the file and line; nothing changes.
    const QString bad = dir.filePath("bad.csv");
    std::ofstream(bad.toStdString()) << "CP1,1,2\n";
    QVERIFY(!window.ImportControl(bad));
    auto* box = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(box != nullptr);
    QVERIFY2(box->text().contains("bad.csv, line 1"), qPrintable(box->text()));
    box->close();
    QCOMPARE(static_cast<int>(window.project().control.size()), 4);

    // A good one replaces the control and drops the residuals (they were against the old points);
    // undo brings both back.
    const QString good = dir.filePath("control.csv");
    std::ofstream(good.toStdString()) << "name,E,N,H\nA,1,2,3\nB,4,5,6\nC,7,8,9.5\n";
    QVERIFY(window.ImportControl(good));
    QCOMPARE(static_cast<int>(window.project().control.size()), 3);
    QVERIFY(!window.project().georef.has_value());
    QCOMPARE(table->rowCount(), 3);
    QVERIFY2(panel->summary().contains("not placed"), qPrintable(panel->summary()));
    window.undoStack()->undo();
    QCOMPARE(static_cast<int>(window.project().control.size()), 4);
    QVERIFY(window.project().georef.has_value());
    QCOMPARE(table->rowCount(), 4);
  }
};

QTEST_MAIN(ControlPanelTest)
#include "control_panel_test.moc"
