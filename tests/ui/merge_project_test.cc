// Drives the real main window under Xvfb for the merge panel, the project menus and the 3D view:
// merge the registered demo project on the worker and export the mesh (re-read with VTK's readers),
// cancel a merge, recent projects, new project / add scans, per-scan visibility, level of detail,
// remembered options and `scanreg --screenshots`. A small street (4 stations, 1000 x 250) is
// simulated and registered once; the tests open the saved registration.
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor.h>
#include <vtkOBJReader.h>
#include <vtkPLYReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkSTLReader.h>
#include <QCheckBox>
#include <QDir>
#include <QDockWidget>
#include <QElapsedTimer>
#include <QMenu>
#include <QLabel>
#include <QMessageBox>
#include <QSettings>
#include <QSignalSpy>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QStatusBar>
#include <QTextStream>
#include <QTimer>
#include <QtTest/QtTest>

#include <array>
#include <cmath>
#include <set>

#include "core/io/project.h"
#include "core/pipeline/create_project.h"
#include "core/report/report.h"
#include "tests/support/test_paths.h"
#include "ui/app_settings.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/merge_panel.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"
#include "ui/scan_cloud_actors.h"
#include "ui/scan_scene.h"
#include "ui/screenshot_tour.h"

using scanreg::ui::JobRunner;
using scanreg::ui::MainWindow;

namespace {

// Waits for the running job; returns true when it succeeded.
bool WaitForJob(MainWindow& window, int timeout_ms, bool* cancelled = nullptr) {
  QSignalSpy ok(window.jobs(), &JobRunner::Succeeded);
  QSignalSpy failed(window.jobs(), &JobRunner::Failed);
  QElapsedTimer timer;
  timer.start();
  while (ok.isEmpty() && failed.isEmpty() && timer.elapsed() < timeout_ms) QTest::qWait(50);
  if (!failed.isEmpty() && cancelled) *cancelled = failed.first().at(2).toBool();
  return !ok.isEmpty();
}

// A coarse, quick merge of the demo street: TSDF, 25 cm voxels, returns within 15 m.
scanreg::merge::MergeOptions QuickMerge() {
  scanreg::merge::MergeOptions options;
  options.method = scanreg::merge::MergeMethod::kTsdf;
  options.voxel_m = 0.25;
  options.max_range_m = 15.0;
  return options;
}

// A colour from a point's position, so that every drawn point can be checked on its own.
std::array<int, 3> ColourAt(double x, double y, double z) {
  const long k = std::lround(x * 1000) * 7 + std::lround(y * 1000) * 13 + std::lround(z * 1000) * 3;
  return std::array<int, 3>{int(k % 251), int((k / 3) % 256), int((k / 7) % 253)};
}

// A Leica-style PTX of 30 x 20 "x y z i [r g b]" lines 4 - 4.5 m in front of a scanner at (x0, 0, 0)
// (identity header pose, the points shifted), coloured by ColourAt; its path, empty on failure.
QString WriteTestPtx(const QTemporaryDir& dir, const QString& name, bool coloured, double x0) {
  QFile f(dir.filePath(name));
  if (!f.open(QIODevice::WriteOnly)) return QString();
  QTextStream out(&f);
  out << "30\n20\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";  // identity pose
  for (int c = 0; c < 30; ++c) {
    for (int r = 0; r < 20; ++r) {
      const double az = (c - 15) * 0.02, el = (r - 10) * 0.02, range = 4.0 + 0.05 * ((r * 7 + c * 3) % 11);
      const double x = x0 + range * std::cos(el) * std::cos(az), y = range * std::cos(el) * std::sin(az),
                   z = range * std::sin(el);
      out << QString::asprintf("%.3f %.3f %.3f %.3f", x, y, z, 0.1 + 0.8 * ((r + c) % 10) / 9.0);
      if (coloured) {
        const auto rgb = ColourAt(std::round(x * 1000) / 1000, std::round(y * 1000) / 1000, std::round(z * 1000) / 1000);
        out << QString::asprintf(" %d %d %d", rgb[0], rgb[1], rgb[2]);
      }
      out << "\n";
    }
  }
  return f.fileName();
}

vtkSmartPointer<vtkPolyData> ReadMesh(const QString& path) {
  const std::string file = path.toStdString();
  vtkSmartPointer<vtkPolyDataAlgorithm> reader;
  if (path.endsWith(".ply")) {
    auto r = vtkSmartPointer<vtkPLYReader>::New();
    r->SetFileName(file.c_str());
    reader = r;
  } else if (path.endsWith(".stl")) {
    auto r = vtkSmartPointer<vtkSTLReader>::New();
    r->SetFileName(file.c_str());
    r->MergingOff();
    reader = r;
  } else {
    auto r = vtkSmartPointer<vtkOBJReader>::New();
    r->SetFileName(file.c_str());
    reader = r;
  }
  reader->Update();
  return reader->GetOutput();
}

// Standard deviation of the grey level, and the fraction of pixels of the most common colour.
std::pair<double, double> ImageSpread(const QImage& image) {
  QHash<QRgb, int> counts;
  double sum = 0, sum2 = 0;
  const int n = image.width() * image.height();
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const QRgb c = image.pixel(x, y);
      const double g = qGray(c);
      sum += g, sum2 += g * g;
      ++counts[c];
    }
  }
  int most = 0;
  for (int c : counts) most = std::max(most, c);
  const double mean = sum / n;
  return {std::sqrt(std::max(0.0, sum2 / n - mean * mean)), double(most) / n};
}

QStringList FilesIn(const QString& dir) { return QDir(dir).entryList(QDir::Files, QDir::Name); }

// Rows of the scan list that hold registered scans (those drawn in the 3D view).
std::vector<int> RegisteredRows(const MainWindow& window) {
  std::vector<int> rows;
  for (std::size_t i = 0; i < window.project().scans.size(); ++i)
    if (window.project().scans[i].registered) rows.push_back(static_cast<int>(i));
  return rows;
}

QString NameOf(const MainWindow& window, int row) { return QString::fromStdString(window.project().scans[row].name); }

}  // namespace

class MergeProjectTest : public QObject {
  Q_OBJECT

 private slots:
  void initTestCase() {
    QVERIFY(demo_.isValid());
    scanreg::SimulatedProjectOptions options;
    options.stations = 4;
    options.scanner.cols = 1000;
    options.scanner.rows = 250;
    scanreg::NullProgress progress;
    const auto simulated = scanreg::pipeline::WriteSimulatedProject(options, demo_.filePath("demo").toStdString(),
                                                                    progress, scanreg::CancelToken());
    QVERIFY(simulated.ok());
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(simulated->file.string())));
    QVERIFY(WaitForJob(window, 600000));
    QVERIFY(window.RegisterProject());
    QVERIFY(WaitForJob(window, 600000));
    registered_ = demo_.filePath("demo/registered.scanreg.json");
    QVERIFY(window.SaveProject(registered_));
    int n = 0;
    for (const auto& s : window.project().scans) n += s.registered;
    QVERIFY2(n >= 3, qPrintable(QString("%1 of 4 scans registered").arg(n)));
  }

  void init() { QSettings().clear(); }  // each test starts from empty settings

  void MergePanelStartsFromMergeOptionsDefaults() {
    MainWindow window;
    const scanreg::merge::MergeOptions defaults, shown = window.mergePanel()->Options();
    QCOMPARE(int(shown.method), int(defaults.method));
    QCOMPARE(shown.voxel_m, defaults.voxel_m);
    QCOMPARE(shown.smooth_iterations, defaults.smooth_iterations);
    QCOMPARE(shown.max_range_m, defaults.max_range_m);
    QCOMPARE(shown.remove_small_pieces, defaults.remove_small_pieces);
  }

  void MergePanelShowsWhatTheMergeWillTakeBeforeItStarts() {
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    auto* estimate = window.findChild<QLabel*>("MergeEstimate");
    QVERIFY(estimate != nullptr);
    // The blocks the estimate counts, read from its line: "... (N blocks of 8^3 voxels)".
    auto blocks = [&] {
      const QString text = estimate->text();
      const int close = text.lastIndexOf(" blocks");
      const int open = text.lastIndexOf('(', close);
      return text.mid(open + 1, close - open - 1).remove('~').toLongLong();
    };
    // Counted only while the Merge tab is shown: behind the scan list, options that change leave
    // no estimate; it is counted when the tab comes to the front.
    QDockWidget *merge_dock = nullptr, *scans_dock = nullptr;
    for (QWidget* w = window.mergePanel(); w && !merge_dock; w = w->parentWidget())
      merge_dock = qobject_cast<QDockWidget*>(w);
    for (QDockWidget* d : window.findChildren<QDockWidget*>())
      if (d->windowTitle() == "Scans") scans_dock = d;
    QVERIFY(merge_dock != nullptr && scans_dock != nullptr);
    scans_dock->raise();
    QTRY_VERIFY(window.mergePanel()->visibleRegion().isEmpty());
    scanreg::merge::MergeOptions options = QuickMerge();
    window.mergePanel()->SetOptions(options);
    QTest::qWait(1000);
    QVERIFY2(!estimate->text().contains("about"), qPrintable(estimate->text()));
    merge_dock->raise();
    QTRY_VERIFY(!window.mergePanel()->visibleRegion().isEmpty());
    QTRY_VERIFY_WITH_TIMEOUT(estimate->text().contains("about"), 5000);
    const long long coarse = blocks();
    QVERIFY2(coarse > 0, qPrintable(estimate->text()));
    options.voxel_m /= 2;  // about four times the blocks on a surface
    window.mergePanel()->SetOptions(options);
    QTRY_VERIFY_WITH_TIMEOUT(blocks() != coarse, 5000);
    QVERIFY2(blocks() > 2.5 * coarse && blocks() < 6 * coarse,
             qPrintable(QString("%1 then %2 blocks").arg(coarse).arg(blocks())));
    QVERIFY(window.mergePanel()->Run());
    QVERIFY(WaitForJob(window, 300000));
  }

  // A 15 cm object (the Stanford bunny's ten range scans at their bun.conf poses): the panel sizes
  // the voxel and the range noise to it (about a millimetre, not a street's 2 cm and 12 mm) and
  // says so; a voxel the user sets gets the default range noise back.
  void MergePanelSizesTheVoxelAndNoiseToASmallObject() {
    const std::filesystem::path data = scanreg::test::RealDataDir();
    if (data.empty()) QSKIP("real data not found (tests/data/realdata)");
    QTemporaryDir dir;
    scanreg::pipeline::CreateProjectOptions create;
    for (const char* name : {"bun000", "bun045", "bun090", "bun180", "bun270", "bun315", "chin", "ear_back", "top2", "top3"})
      create.scan_files.push_back(data / "stanford_bunny" / (std::string(name) + ".ply"));
    create.poses = data / "stanford_bunny" / "bun.conf";
    scanreg::NullProgress progress;
    scanreg::CancelToken cancel;
    const std::filesystem::path path = dir.filePath("bunny.scanreg.json").toStdString();
    QVERIFY(scanreg::pipeline::CreateProject(path, create, progress, cancel).ok());
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(QString::fromStdString(path.string())));
    QVERIFY(WaitForJob(window, 120000));
    for (QDockWidget* d : window.findChildren<QDockWidget*>())
      if (d->windowTitle() == "Merge") d->raise();
    auto* estimate = window.findChild<QLabel*>("MergeEstimate");
    QVERIFY(estimate != nullptr);
    QTRY_VERIFY_WITH_TIMEOUT(estimate->text().contains("sized for this project"), 30000);
    const scanreg::merge::MergeOptions sized = window.mergePanel()->Options();
    QVERIFY2(sized.voxel_m <= 0.002, qPrintable(QString::number(sized.voxel_m)));
    QVERIFY2(sized.sigma_m <= 0.002, qPrintable(QString::number(sized.sigma_m)));
    scanreg::merge::MergeOptions chosen = sized;
    chosen.voxel_m = 0.005;
    window.mergePanel()->SetOptions(chosen);
    QCOMPARE(window.mergePanel()->Options().voxel_m, 0.005);
    QCOMPARE(window.mergePanel()->Options().sigma_m, scanreg::merge::MergeOptions().sigma_m);
  }

  void MergeThenExportPlyObjStlAndReadBack() {
    MainWindow window;
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QVERIFY(!window.mergePanel()->Run());  // no project: a dialog names the next step
    auto* box = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(box != nullptr);
    QVERIFY2(box->text().contains("Open a project"), qPrintable(box->text()));
    box->close();

    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    window.mergePanel()->SetOptions(QuickMerge());
    QVERIFY(window.mergePanel()->Run());
    QVERIFY(WaitForJob(window, 300000));
    QVERIFY(window.mergePanel()->mesh() != nullptr);
    const auto triangles = static_cast<vtkIdType>(window.mergePanel()->mesh()->triangle_count());
    QVERIFY2(triangles > 1000, qPrintable(QString("%1 triangles").arg(triangles)));
    // Within the preview budget the 3D view shows the whole mesh: the same triangles, with normals.
    const scanreg::merge::Mesh* mesh = window.mergePanel()->preview();
    QVERIFY(mesh != nullptr);
    QCOMPARE(static_cast<vtkIdType>(mesh->triangles.size()), triangles);
    vtkActor* actor = window.scene()->MeshActor();
    QVERIFY(actor != nullptr);
    auto* poly = vtkPolyData::SafeDownCast(actor->GetMapper()->GetInput());
    QCOMPARE(poly->GetNumberOfPolys(), triangles);
    QVERIFY(poly->GetPointData()->GetNormals() != nullptr);
    // Every vertex lies within the merge's range of a registered scanner, give or take the field's
    // band and a voxel (the surface is interpolated that far beyond the last sample).
    double worst = 0;
    for (const Eigen::Vector3f& v : mesh->vertices) {
      double nearest = 1e9;
      for (const auto& s : window.project().scans)
        if (s.registered)
          nearest = std::min(nearest, (mesh->origin + v.cast<double>() - s.world_from_scan.translation()).norm());
      worst = std::max(worst, nearest);
    }
    const double reach = QuickMerge().max_range_m + QuickMerge().Band() + QuickMerge().voxel_m;
    QVERIFY2(worst < reach, qPrintable(QString("a vertex %1 m from every scanner").arg(worst)));

    // Scans / mesh toggles.
    const QString name = NameOf(window, RegisteredRows(window).front());
    QVERIFY(window.scene()->CloudActor(name) != nullptr);
    auto* show_scans = window.mergePanel()->findChild<QCheckBox*>("ShowScans");
    show_scans->setChecked(false);
    QVERIFY(!window.scene()->CloudActor(name)->GetVisibility());
    QVERIFY(actor->GetVisibility());
    show_scans->setChecked(true);
    QVERIFY(window.scene()->CloudActor(name)->GetVisibility());

    QTemporaryDir out;
    vtkActor* cloud = window.scene()->CloudActor(name);
    for (const QString file : {"mesh.ply", "mesh.obj", "mesh.stl"}) {
      const QString path = out.filePath(file);
      QVERIFY(window.mergePanel()->ExportMesh(path));
      QVERIFY(WaitForJob(window, 120000));
      const vtkSmartPointer<vtkPolyData> read = ReadMesh(path);
      QCOMPARE(read->GetNumberOfPolys(), triangles);
    }
    QCOMPARE(FilesIn(out.path()), QStringList({"mesh.obj", "mesh.ply", "mesh.stl"}));  // no temporary left
    QCOMPARE(window.scene()->CloudActor(name), cloud);  // the exports did not rebuild the clouds
    QVERIFY(!window.dirty());                           // merging does not change the project

    // Beyond the preview budget the view shows the mesh simplified, and Export still writes it whole.
    window.mergePanel()->SetPreviewTriangles(std::size_t(triangles / 10));
    QVERIFY(window.mergePanel()->Run());
    QVERIFY(WaitForJob(window, 300000));
    QCOMPARE(static_cast<vtkIdType>(window.mergePanel()->mesh()->triangle_count()), triangles);
    const scanreg::merge::Mesh* simplified = window.mergePanel()->preview();
    QVERIFY(simplified != nullptr);
    const auto shown = static_cast<vtkIdType>(simplified->triangles.size());
    QVERIFY2(shown <= triangles / 10 && shown > triangles / 100,
             qPrintable(QString("%1 of %2 triangles shown").arg(shown).arg(triangles)));
    auto* shown_poly = vtkPolyData::SafeDownCast(window.scene()->MeshActor()->GetMapper()->GetInput());
    QCOMPARE(shown_poly->GetNumberOfPolys(), shown);
    QVERIFY2(window.mergePanel()->findChild<QLabel*>("MergeSummary")->text().contains("simplified"),
             qPrintable(window.mergePanel()->findChild<QLabel*>("MergeSummary")->text()));
    QVERIFY(window.mergePanel()->ExportMesh(out.filePath("whole.ply")));
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(ReadMesh(out.filePath("whole.ply"))->GetNumberOfPolys(), triangles);
    // The simplified surface lies on the whole one's: its world bounds within a few of its cells.
    double whole_bounds[6];
    ReadMesh(out.filePath("whole.ply"))->GetBounds(whole_bounds);
    Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
    for (const Eigen::Vector3f& v : simplified->vertices) {
      low = low.cwiseMin(simplified->origin + v.cast<double>());
      high = high.cwiseMax(simplified->origin + v.cast<double>());
    }
    const double cell = 16 * QuickMerge().voxel_m;  // the preview cell is ~4 voxels (a tenth of the triangles)
    for (int k = 0; k < 3; ++k) {
      QVERIFY2(std::abs(low[k] - whole_bounds[2 * k]) < cell && std::abs(high[k] - whole_bounds[2 * k + 1]) < cell,
               qPrintable(QString("axis %1: shown %2..%3, whole %4..%5")
                              .arg(k).arg(low[k]).arg(high[k]).arg(whole_bounds[2 * k]).arg(whole_bounds[2 * k + 1])));
    }
    QVERIFY(QFile::remove(out.filePath("whole.ply")));

    // An edit of the registration drops the mesh: it no longer matches the poses.
    window.document()->Edit("move nothing", window.project());
    QVERIFY(window.mergePanel()->mesh() == nullptr);
    QVERIFY(window.scene()->MeshActor() == nullptr);
    QVERIFY(!window.mergePanel()->ExportMesh(out.filePath("stale.ply")));
  }

  void CancelledMergeLeavesNoMeshNoFileAndTheProjectUnchanged() {
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    const QStringList files_before = FilesIn(QFileInfo(registered_).path());
    std::vector<Eigen::Matrix4d> poses;
    for (const auto& s : window.project().scans) poses.push_back(s.world_from_scan.matrix());
    window.mergePanel()->SetOptions(QuickMerge());
    QVERIFY(window.mergePanel()->Run());
    window.jobs()->Cancel();
    bool cancelled = false;
    QVERIFY(!WaitForJob(window, 300000, &cancelled));
    QVERIFY(cancelled);
    QVERIFY(window.mergePanel()->mesh() == nullptr);
    QVERIFY(window.scene()->MeshActor() == nullptr);
    QVERIFY(!window.mergePanel()->ExportMesh(QDir::temp().filePath("never.ply")));
    QVERIFY(!QFile::exists(QDir::temp().filePath("never.ply")));
    QCOMPARE(FilesIn(QFileInfo(registered_).path()), files_before);
    QVERIFY(!window.dirty());
    for (std::size_t i = 0; i < poses.size(); ++i)
      QVERIFY(window.project().scans[i].world_from_scan.matrix() == poses[i]);
  }

  void MergeOptionsAndWindowLayoutAreRemembered() {
    scanreg::merge::MergeOptions chosen = QuickMerge();
    chosen.smooth_iterations = 2;
    chosen.remove_small_pieces = false;
    QSize size;
    {
      MainWindow window;
      window.show();
      QVERIFY(QTest::qWaitForWindowExposed(&window));
      window.resize(1320, 930);
      size = window.size();  // at least the docks' minimum sizes
      window.mergePanel()->SetOptions(chosen);
      QVERIFY(!window.mergePanel()->Run());  // nothing to merge, but the choice is kept
      window.findChild<QDockWidget*>("LogDock")->hide();
      QTest::qWait(100);
      QVERIFY(window.close());
    }
    MainWindow again;
    const scanreg::merge::MergeOptions shown = again.mergePanel()->Options();
    QCOMPARE(int(shown.method), int(chosen.method));
    QCOMPARE(shown.voxel_m, chosen.voxel_m);
    QCOMPARE(shown.max_range_m, chosen.max_range_m);
    QCOMPARE(shown.smooth_iterations, 2);
    QCOMPARE(shown.remove_small_pieces, false);
    QCOMPARE(again.size(), size);
    QVERIFY(again.findChild<QDockWidget*>("LogDock")->isHidden());
  }

  void RecentProjectsHoldTheReopenedProjectAndDropMissingOnes() {
    MainWindow window;
    window.show();
    scanreg::ui::AddRecentProject(demo_.filePath("gone.scanreg.json"));  // no such file
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    const QString absolute = QFileInfo(registered_).absoluteFilePath();
    QStringList recent = scanreg::ui::RecentProjects();
    QCOMPARE(recent.first(), absolute);
    QCOMPARE(recent.count(absolute), 1);
    QCOMPARE(recent.size(), 2);

    auto* menu = window.findChild<QMenu*>("RecentMenu");
    QVERIFY(menu != nullptr);
    emit menu->aboutToShow();
    QCOMPARE(menu->actions().size(), 1);  // the missing project is gone
    QVERIFY(menu->actions().first()->text().startsWith("registered.scanreg.json"));
    QCOMPARE(scanreg::ui::RecentProjects(), QStringList({absolute}));

    for (int i = 0; i < scanreg::ui::kMaxRecentProjects + 3; ++i)
      scanreg::ui::AddRecentProject(demo_.filePath(QString("p%1.scanreg.json").arg(i)));
    QCOMPARE(scanreg::ui::RecentProjects().size(), scanreg::ui::kMaxRecentProjects);
  }

  void NewProjectAndAddScansReadTheFilesOnTheWorker() {
    MainWindow window;
    window.show();
    QTemporaryDir dir;
    const QString demo = QFileInfo(registered_).path();
    const QString path = dir.filePath("street.scanreg.json");
    QVERIFY(window.NewProject({demo + "/s01.ptx", demo + "/s02.ptx"}, path));
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(static_cast<int>(window.project().scans.size()), 2);
    QCOMPARE(static_cast<int>(window.previews().size()), 2);
    QVERIFY(QFile::exists(path));
    QVERIFY(!window.dirty());

    // s01.ptx is already in the project: left out and listed; s03 is added.
    QVERIFY(window.AddScans({demo + "/s03.ptx", demo + "/s01.ptx"}));
    QVERIFY(WaitForJob(window, 120000));
    QStringList names;
    for (const auto& s : window.project().scans) names << QString::fromStdString(s.name);
    QCOMPARE(names, QStringList({"s01", "s02", "s03"}));
    QCOMPARE(QString::fromStdString(window.previews()[2].scan.name), QString("s03"));
    QVERIFY(window.previews()[2].full_valid > 0);
    QCOMPARE(window.scanList()->rowCount(), 3);
    QVERIFY(window.dirty());
    auto* twice = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(twice != nullptr);
    QVERIFY2(twice->text().contains("s01.ptx") && twice->text().contains("already in the project"),
             qPrintable(twice->text()));
    twice->close();

    // A bad file: a dialog naming it; the project keeps its three scans.
    const QString bad = dir.filePath("bad.ptx");
    QFile f(bad);
    QVERIFY(f.open(QIODevice::WriteOnly));
    f.write("not a ptx\n");
    f.close();
    QVERIFY(window.AddScans({bad}));
    QVERIFY(WaitForJob(window, 120000));
    auto* box = window.findChild<QMessageBox*>("ErrorDialog");
    QVERIFY(box != nullptr);
    QVERIFY2(box->text().contains("bad.ptx"), qPrintable(box->text()));
    QCOMPARE(static_cast<int>(window.project().scans.size()), 3);

    // Unsaved changes: Cancel keeps them, Discard lets the next action go on.
    for (const auto& [button, expected] :
         {std::make_pair(QMessageBox::Cancel, false), std::make_pair(QMessageBox::Discard, true)}) {
      QTimer::singleShot(200, &window, [&window, button = button] {
        auto* prompt = window.findChild<QMessageBox*>("UnsavedChangesDialog");
        if (prompt) prompt->button(button)->click();
      });
      QCOMPARE(window.MaybeSaveChanges(), expected);
    }
  }

  void UncheckingAScanHidesItsActor() {
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    const std::vector<int> rows = RegisteredRows(window);
    QVERIFY(rows.size() >= 2);
    const QString a = NameOf(window, rows[0]), b = NameOf(window, rows[1]);
    QTableWidgetItem* item = window.scanList()->item(rows[0], 0);
    QCOMPARE(item->text(), a);
    QCOMPARE(item->checkState(), Qt::Checked);
    vtkActor* before = window.scene()->CloudActor(a);
    QVERIFY(before != nullptr && before->GetVisibility());
    item->setCheckState(Qt::Unchecked);
    QVERIFY(!window.scene()->CloudActor(a)->GetVisibility());
    QVERIFY(window.scene()->CloudActor(b)->GetVisibility());
    // Rebuilt actors (colour by reflectance) keep the choice, and so does the list.
    window.findChild<QAction*>("ColourByReflectance")->setChecked(true);
    QVERIFY(window.scene()->CloudActor(a) != before);
    QVERIFY(!window.scene()->CloudActor(a)->GetVisibility());
    QCOMPARE(window.scanList()->item(rows[0], 0)->checkState(), Qt::Unchecked);
    window.scanList()->item(rows[0], 0)->setCheckState(Qt::Checked);
    QVERIFY(window.scene()->CloudActor(a)->GetVisibility());
  }

  // View → Colour points by → Scanner colour draws each point in the colour its file gives it (a
  // Leica-style PTX of "x y z i r g b" lines); a scan without colour is drawn grey by its
  // reflectance, and the status bar says how many scans have colour. The choice is remembered.
  void ScannerColourIsDrawnAndScansWithoutColourAreGrey() {
    QTemporaryDir dir;
    const QString coloured = WriteTestPtx(dir, "camera.ptx", true, 0.0), grey = WriteTestPtx(dir, "plain.ptx", false, 0.5);
    QVERIFY(!coloured.isEmpty() && !grey.isEmpty());
    MainWindow window;
    window.show();
    QVERIFY(window.NewProject({coloured, grey}, dir.filePath("c.scanreg.json")));
    QVERIFY(WaitForJob(window, 120000));
    QCOMPARE(static_cast<int>(window.project().scans.size()), 2);
    QVERIFY(window.previews()[0].scan.HasColour());
    QVERIFY(!window.previews()[1].scan.HasColour());
    window.findChild<QAction*>("ColourPerScan")->setChecked(true);
    window.findChild<QAction*>("ColourByScannerColour")->setChecked(true);
    QVERIFY2(window.statusBar()->currentMessage().contains("1 of 2"), qPrintable(window.statusBar()->currentMessage()));
    QCOMPARE(QSettings().value("view/colouring").toString(), QString("colour"));
    const auto drawn = [&](const QString& scan) {
      std::vector<std::pair<Eigen::Vector3d, std::array<int, 3>>> points;
      vtkActor* actor = window.scene()->CloudActor(scan);
      if (!actor) return points;
      vtkPolyData* poly = vtkPolyDataMapper::SafeDownCast(actor->GetMapper())->GetInput();
      vtkDataArray* scalars = poly->GetPointData()->GetScalars();
      for (vtkIdType i = 0; i < poly->GetNumberOfPoints(); ++i) {
        double p[3];
        poly->GetPoint(i, p);
        points.push_back({Eigen::Vector3d(p[0], p[1], p[2]),
                          {int(scalars->GetComponent(i, 0)), int(scalars->GetComponent(i, 1)), int(scalars->GetComponent(i, 2))}});
      }
      return points;
    };
    // Both scans stand at the origin, which is the scene's origin too: drawn points are world points.
    const auto camera = drawn("camera"), plain = drawn("plain");
    QCOMPARE(camera.size(), window.previews()[0].scan.CountPoints());
    QCOMPARE(plain.size(), window.previews()[1].scan.CountPoints());
    int wrong = 0, coloured_points = 0;
    for (const auto& [p, rgb] : camera) {
      const auto want = ColourAt(std::round(p.x() * 1000) / 1000, std::round(p.y() * 1000) / 1000,
                                  std::round(p.z() * 1000) / 1000);
      wrong += rgb != want;
      coloured_points += rgb[0] != rgb[1] || rgb[1] != rgb[2];
    }
    QCOMPARE(wrong, 0);
    QVERIFY(coloured_points > int(camera.size()) / 2);  // not drawn grey
    for (const auto& [p, rgb] : plain) QVERIFY(rgb[0] == rgb[1] && rgb[1] == rgb[2]);
    std::set<std::array<int, 3>> greys;
    for (const auto& [p, rgb] : plain) greys.insert(rgb);
    QVERIFY(greys.size() >= 5);  // reflectance, not one flat colour

    // Back to one colour per scan; the next window starts with the choice last made.
    window.findChild<QAction*>("ColourPerScan")->setChecked(true);
    std::set<std::array<int, 3>> per_scan;
    for (const auto& [p, rgb] : drawn("camera")) per_scan.insert(rgb);
    QCOMPARE(static_cast<int>(per_scan.size()), 1);
    window.findChild<QAction*>("ColourByScannerColour")->setChecked(true);
    MainWindow next;
    QVERIFY(next.findChild<QAction*>("ColourByScannerColour")->isChecked());
    QVERIFY(next.scene()->colouring() == scanreg::ui::CloudColouring::kScannerColour);
    next.findChild<QAction*>("ColourPerScan")->setChecked(true);  // the other tests start per scan
  }

  // The merged mesh is drawn in the scanners' colour under View -> Colour points by -> Scanner
  // colour: every vertex takes the colour of a point of the coloured PTX (one scan: registered at
  // its file's pose); the summary says so, and how much of the surface was interpolated; per scan,
  // the mesh is plaster grey.
  void MergedMeshIsDrawnInTheScannersColour() {
    QTemporaryDir dir;
    const QString coloured = WriteTestPtx(dir, "camera.ptx", true, 0.0);
    QVERIFY(!coloured.isEmpty());
    MainWindow window;
    window.show();
    QVERIFY(window.NewProject({coloured}, dir.filePath("m.scanreg.json")));
    QVERIFY(WaitForJob(window, 120000));
    window.findChild<QAction*>("ColourByScannerColour")->setChecked(true);
    std::set<std::array<int, 3>> camera_colours;
    const scanreg::Scan& scan = window.previews()[0].scan;
    for (std::size_t i = 0; i < scan.size(); ++i)
      if (scan.valid[i]) camera_colours.insert({scan.colour[i][0], scan.colour[i][1], scan.colour[i][2]});
    QVERIFY(camera_colours.size() > 100);
    scanreg::merge::MergeOptions merge_options = QuickMerge();
    merge_options.voxel_m = 0.05;
    window.mergePanel()->SetOptions(merge_options);
    QVERIFY(window.mergePanel()->Run());
    QVERIFY(WaitForJob(window, 120000));
    QVERIFY(window.mergePanel()->mesh() != nullptr && window.mergePanel()->mesh()->coloured());
    const QString summary = window.mergePanel()->findChild<QLabel*>("MergeSummary")->text();
    QVERIFY2(summary.contains("scanners' colour") && summary.contains("interpolated"), qPrintable(summary));
    const auto mesh_colours = [&]() -> vtkDataArray* {
      auto* poly = vtkPolyData::SafeDownCast(window.scene()->MeshActor()->GetMapper()->GetInput());
      return window.scene()->MeshActor()->GetMapper()->GetScalarVisibility() ? poly->GetPointData()->GetScalars()
                                                                              : nullptr;
    };
    vtkDataArray* vertex_rgb = mesh_colours();
    QVERIFY(vertex_rgb != nullptr && vertex_rgb->GetNumberOfTuples() > 20);
    int from_camera = 0;
    for (vtkIdType i = 0; i < vertex_rgb->GetNumberOfTuples(); ++i) {
      from_camera += camera_colours.count({int(vertex_rgb->GetComponent(i, 0)), int(vertex_rgb->GetComponent(i, 1)),
                                           int(vertex_rgb->GetComponent(i, 2))});
    }
    QCOMPARE(from_camera, int(vertex_rgb->GetNumberOfTuples()));
    window.findChild<QAction*>("ColourPerScan")->setChecked(true);  // the other tests start per scan
    QVERIFY(mesh_colours() == nullptr);
  }

  void DecimatedByDefaultFullResolutionOnDemand() {
    MainWindow window;
    window.show();
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    std::size_t valid = 0;
    for (std::size_t i = 0; i < window.previews().size(); ++i)
      if (window.project().scans[i].registered) valid += window.previews()[i].scan.CountValid();
    QCOMPARE(window.scene()->decimatedPoints(), scanreg::ui::ScanScene::kDecimatedPoints);
    // A budget of a fifth of the points stands for a project of millions.
    const std::size_t budget = valid / 5;
    window.scene()->SetDecimatedPoints(budget);
    const std::size_t drawn = window.scene()->DrawnPoints();
    QVERIFY2(drawn <= budget && drawn > budget * 8 / 10, qPrintable(QString("%1 drawn of %2").arg(drawn).arg(valid)));
    window.findChild<QAction*>("FullResolution")->setChecked(true);
    QCOMPARE(window.scene()->DrawnPoints(), valid);
    window.findChild<QAction*>("FullResolution")->setChecked(false);
    QCOMPARE(window.scene()->DrawnPoints(), drawn);
  }

  void ExportReportWritesThePageOnTheWorker() {
    MainWindow window;
    window.show();
    QVERIFY(!window.ExportReport(demo_.filePath("no-project-report")));  // nothing to report
    QVERIFY(window.OpenProject(registered_));
    QVERIFY(WaitForJob(window, 120000));
    QTemporaryDir out;
    QVERIFY(window.ExportReport(out.filePath("report")));
    QVERIFY(WaitForJob(window, 120000));
    QFile index(out.filePath("report/index.html"));
    QVERIFY(index.open(QIODevice::ReadOnly));
    const QString html = QString::fromUtf8(index.readAll());
    for (const auto& s : window.project().scans) QVERIFY(html.contains(QString::fromStdString(s.name)));
    QVERIFY(QFileInfo(out.filePath("report/") + scanreg::report::kNetworkPng).size() > 1000);
    QVERIFY(!QFile::exists(demo_.filePath("no-project-report")));
  }

  void ScreenshotsAreWrittenAndNotBlank() {
    MainWindow window;
    window.resize(1400, 900);
    window.show();
    QVERIFY(QTest::qWaitForWindowExposed(&window));
    QTemporaryDir out;
    scanreg::ui::ScreenshotTour tour(&window, out.path(), QuickMerge());
    QSignalSpy finished(&tour, &scanreg::ui::ScreenshotTour::Finished);
    tour.Start(registered_);
    QVERIFY(finished.wait(600000));
    QVERIFY2(finished.first().at(0).toBool(), qPrintable(finished.first().at(1).toString()));
    const auto views = scanreg::ui::ScreenshotViews();
    QCOMPARE(FilesIn(out.path()).size(), static_cast<int>(views.size()));
    for (const auto& view : views) {
      const QImage image(out.filePath(view.file));
      QVERIFY2(!image.isNull(), qPrintable(view.file));
      QVERIFY2(image.width() >= 120 && image.height() >= 100, qPrintable(view.file));
      const auto [spread, most] = ImageSpread(image);
      QVERIFY2(spread > 8.0 && most < 0.99,
               qPrintable(QString("%1: grey spread %2, most common colour %3").arg(view.file).arg(spread).arg(most)));
    }
  }

 private:
  QTemporaryDir demo_;
  QString registered_;
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  // Settings of their own, in a temporary folder: the tests neither read nor change the user's.
  QTemporaryDir settings;
  QSettings::setDefaultFormat(QSettings::IniFormat);
  QSettings::setPath(QSettings::IniFormat, QSettings::UserScope, settings.path());
  QApplication::setOrganizationName("scanreg-test");
  QApplication::setApplicationName("merge-project-test");
  MergeProjectTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "merge_project_test.moc"
