// Issue 15 in the window: the Control dock shows the last adjustment's residuals graded against
// the tolerance; File → Import control points replaces the project's control as an undoable edit
// and says when the file is bad.
#include <QMessageBox>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QtTest/QtTest>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/io/project.h"
#include "core/pipeline/create_project.h"
#include "tests/ui/wait_for_job.h"
#include <vtkActor.h>
#include <vtkMapper.h>
#include <vtkPolyData.h>

#include <QPushButton>

#include "core/simulate/project_sim.h"
#include "ui/control_panel.h"
#include "ui/main_window.h"
#include "ui/network_panel.h"
#include "ui/pick_target_dialog.h"
#include "ui/project_document.h"
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
        scanreg::ui::MakeScanActors(window.previews(), drawn, scanreg::ui::CloudColouring::kPerScan, 1000);
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

  // Registration → Pick a target in scan…: a click a few pixels off a checkerboard on a façade
  // adds a target at the board's centre (the fit, not the click), named after a control point;
  // undo removes it. Then the project, registered, is georeferenced on control without
  // registering again, and the picked target is among the used ones.
  void PickingATargetAddsIt() {
    QTemporaryDir dir;
    scanreg::SimulatedProjectOptions sim;
    sim.stations = 2;
    sim.checker_targets = 6;
    scanreg::NullProgress progress;
    auto written = scanreg::pipeline::WriteSimulatedProject(sim, dir.filePath("p").toStdString(), progress,
                                                           scanreg::CancelToken());
    QVERIFY(written.ok());
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(written->file.string())));
    QVERIFY(WaitForJob(window, 120000));
    QVERIFY(window.ImportControl(QString::fromStdString((written->file.parent_path() / "control.csv").string())));

    // The nearest board s01 sees (not behind a car or a tree), and the pixel it shows at (column:
    // azimuth, row: elevation).
    const scanreg::io::ProjectScan& s01 = window.project().scans[0];
    QVERIFY(s01.reference_world_from_scan.has_value());
    const Eigen::Isometry3d scan_from_world = s01.reference_world_from_scan->inverse();
    const scanreg::Expected<scanreg::Scan> full = window.document()->ReadScan(0);  // targets are picked in full
    QVERIFY(full.ok());
    const scanreg::Scan& scan = *full;
    auto pixel_of = [&](const Eigen::Vector3d& p) {
      const double az = std::atan2(p.y(), p.x()), el = std::asin(p.z() / p.norm());
      const double col = (az + M_PI) / (2 * M_PI / sim.scanner.cols) - 0.5;
      const double el_step = (sim.scanner.elevation_max_deg - sim.scanner.elevation_min_deg) * M_PI / 180 / sim.scanner.rows;
      return QPointF(col, (sim.scanner.elevation_max_deg * M_PI / 180 - el) / el_step - 0.5);
    };
    const scanreg::SimulatedTarget* nearest = nullptr;
    Eigen::Vector3d truth;
    const std::vector<scanreg::SimulatedTarget> boards = scanreg::SimulatedTargets(sim);
    for (const scanreg::SimulatedTarget& t : boards) {
      const Eigen::Vector3d p = scan_from_world * t.world;
      const QPointF px = pixel_of(p);
      const int r = static_cast<int>(std::lround(px.y())), c = static_cast<int>(std::lround(px.x()));
      if (r < 0 || r >= scan.rows || c < 0 || c >= scan.cols || !scan.IsValid(r, c)) continue;
      if ((scan.Point(r, c).cast<double>() - p).norm() > 0.1 || p.norm() > 15.0) continue;  // hidden or far
      if (!nearest || p.norm() < truth.norm()) nearest = &t, truth = p;
    }
    QVERIFY2(nearest != nullptr, "no board in view of s01");
    const double col = pixel_of(truth).x(), row = pixel_of(truth).y();

    scanreg::ui::PickTargetDialog* dialog = window.PickTarget("s01");
    QVERIFY(dialog != nullptr);
    QVERIFY(dialog->Pick(QPointF(col + 2.5, row - 1.5)));  // a little off, as a hand is
    QVERIFY2(dialog->Status().contains("Checkerboard"), qPrintable(dialog->Status()));
    dialog->SetName(QString::fromStdString(nearest->name));
    auto picked = dialog->Target();
    QVERIFY(picked.has_value());
    QCOMPARE(picked->name, nearest->name);
    QVERIFY2((picked->center - truth).norm() < 0.004,
             qPrintable(QString("%1 mm off").arg((picked->center - truth).norm() * 1000)));
    QTest::mouseClick(dialog->addButton(), Qt::LeftButton);
    auto is_pick = [&](const scanreg::io::TargetRecord& t) {
      return t.kind == "picked" && t.scan == "s01" && t.name == nearest->name && t.named_by_user &&
             (t.center - truth).norm() < 0.004;
    };
    const auto& after = window.project().targets;
    QVERIFY(std::count_if(after.begin(), after.end(), is_pick) == 1);
    window.undoStack()->undo();
    QVERIFY(std::none_of(window.project().targets.begin(), window.project().targets.end(), is_pick));
    window.undoStack()->redo();

    // Register, then georeference again on its own: the pick is used and kept.
    QVERIFY(window.RegisterProject());
    QVERIFY(WaitForJob(window, 300000));
    QVERIFY(window.Georeference());
    QVERIFY(WaitForJob(window, 120000));
    const scanreg::io::Project& placed = window.project();
    QVERIFY(placed.georef.has_value());
    const auto kept = std::find_if(placed.targets.begin(), placed.targets.end(), [&](const auto& t) {
      return t.kind == "picked" && t.name == nearest->name;
    });
    QVERIFY(kept != placed.targets.end());
    QVERIFY2(kept->residual_m >= 0 && kept->residual_m < 0.01, qPrintable(QString::number(kept->residual_m)));
    bool used = false;
    for (const auto& row : placed.georef->control) used = used || (row.name == nearest->name && row.role == "used");
    QVERIFY(used);
    // The network view draws one mark per target (every target is named after the adjustment).
    std::set<std::string> names;
    for (const auto& t : placed.targets) names.insert(t.name);
    auto* network = window.findChild<scanreg::ui::NetworkPanel*>("ScanNetwork");
    QVERIFY(network != nullptr);
    QVERIFY(names.size() >= 3);
    QCOMPARE(network->TargetCount(), static_cast<int>(names.size()));
  }
};

QTEST_MAIN(ControlPanelTest)
#include "control_panel_test.moc"
