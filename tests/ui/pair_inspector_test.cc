// Drives the panorama view, the confusion matrix and the pair panel of the real main window under
// Xvfb, on the simulated demo project (5 stations with known poses), registered once.
#include <QVTKOpenGLNativeWidget.h>
#include <vtkActor2DCollection.h>
#include <vtkRenderer.h>
#include <QComboBox>
#include <QElapsedTimer>
#include <QGraphicsLineItem>
#include <QPushButton>
#include <QSignalSpy>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QGraphicsSimpleTextItem>
#include <QGraphicsLineItem>
#include <QtTest/QtTest>
#include <cmath>

#include "core/features/sift.h"
#include "core/geometry/transform.h"
#include "tests/ui/wait_for_job.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/network_panel.h"
#include "ui/pair_inspector.h"
#include "ui/pair_panel.h"
#include "ui/panorama_view.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"
#include "ui/view_3d.h"

using scanreg::test::WaitForJob;
using scanreg::ui::JobRunner;
using scanreg::ui::MainWindow;

namespace {

void ClickCell(QTableWidget* table, int row, int col) {
  QTableWidgetItem* item = table->item(row, col);
  QVERIFY(item != nullptr);
  table->scrollToItem(item);
  QTest::mouseClick(table->viewport(), Qt::LeftButton, {}, table->visualItemRect(item).center());
}

int RowOf(QTableWidget* table, const QString& name, bool vertical_header) {
  for (int r = 0; r < (vertical_header ? table->rowCount() : table->columnCount()); ++r) {
    const QTableWidgetItem* h = vertical_header ? table->verticalHeaderItem(r) : table->horizontalHeaderItem(r);
    if (h && h->text() == name) return r;
  }
  return -1;
}

// The relative pose the simulator used: parent_from_child from the reference poses.
Eigen::Isometry3d TruePair(const scanreg::io::Project& project, const std::string& parent, const std::string& child) {
  const auto& p = project.scans[project.FindScan(parent)];
  const auto& c = project.scans[project.FindScan(child)];
  return p.reference_world_from_scan->inverse() * *c.reference_world_from_scan;
}

}  // namespace

class PairInspectorTest : public QObject {
  Q_OBJECT

 private slots:
  // A campaign's network stays readable: past 30 scans the nodes are smaller and only the scans that
  // need the user's eye (root, unregistered) are labelled; a small project labels every scan.
  void ALargeNetworkLabelsOnlyTheScansThatNeedAttention() {
    for (const int n : {10, 40}) {
      scanreg::io::Project project;
      for (int i = 0; i < n; ++i) {
        scanreg::io::ProjectScan s;
        s.name = "s" + std::to_string(i);
        s.registered = i != 7;
        s.world_from_scan.translation() = Eigen::Vector3d(10.0 * i, 0, 0);
        project.scans.push_back(s);
      }
      project.root = "s0";
      scanreg::ui::NetworkPanel panel;
      panel.Show(project);
      QCOMPARE(panel.NodeCount(), n);
      int labels = 0;
      for (QGraphicsItem* item : panel.scene()->items()) labels += dynamic_cast<QGraphicsSimpleTextItem*>(item) != nullptr;
      QCOMPARE(labels, n == 10 ? 10 : 2);
    }
  }

  // Issue 14: a pair that failed before its surfaces were compared shows "—", not "0.0 mm".
  void AFailedPairShowsADashForWhatItNeverMeasured() {
    scanreg::ui::PairPanel panel;
    scanreg::pipeline::PairInspection r;
    r.result.link.status = scanreg::io::LinkStatus::kFailed;
    r.result.link.reason = "only 6 of 17 correspondences agree on a pose";
    panel.ShowResult(r);
    QCOMPARE(panel.Evidence("rms"), QString("—"));
    QCOMPARE(panel.Evidence("overlap"), QString("—"));
    QCOMPARE(panel.Evidence("reason"), QString::fromStdString(r.result.link.reason));
    r.result.link.rms_m = 0.05;  // failed after measuring (a high RMS): the figures are shown
    r.result.link.overlap = 0.3;
    panel.ShowResult(r);
    QCOMPARE(panel.Evidence("rms"), QString("50.0 mm"));
    QCOMPARE(panel.Evidence("overlap"), QString("30.0 %"));
  }

  void initTestCase() {
    window_ = new MainWindow;
    window_->show();
    QVERIFY(QTest::qWaitForWindowExposed(window_));
    QElapsedTimer timer;
    timer.start();
    QVERIFY(window_->OpenDemoProject(dir_.filePath("demo")));
    QVERIFY(WaitForJob(*window_, 300000));
    qInfo("demo project: %.1f s", timer.restart() / 1000.0);
    QVERIFY(window_->RegisterProject());
    QVERIFY(WaitForJob(*window_, 600000));
    qInfo("registration: %.1f s", timer.restart() / 1000.0);
    QCOMPARE(window_->confusionPanel()->rowCount(), 5);
    // The chained link with the most coarse inliers: the pair the tests open.
    for (const auto& l : window_->project().links)
      if (!l.loop_check && l.status == scanreg::io::LinkStatus::kOk && l.ransac_inliers > link_.ransac_inliers)
        link_ = l;
    QVERIFY2(!link_.parent.empty(), "the demo registration has an ok link");
  }

  void cleanupTestCase() { delete window_; }

  void SelectingAScanShowsItsPanoramaWithItsKeypoints() {
    const int row = 1;
    const scanreg::Expected<scanreg::Scan> full = window_->document()->ReadScan(row);
    QVERIFY(full.ok());
    const scanreg::Scan& scan = *full;
    ClickCell(window_->scanList(), row, 0);
    QVERIFY(WaitForJob(*window_, 120000));
    scanreg::ui::PanoramaView* view = window_->pairInspector()->panoramaView();
    QCOMPARE(view->ShownScan(), QString::fromStdString(scan.name));
    QCOMPARE(view->ImageSize(), QSize(scan.cols, scan.rows));
    const auto features = scanreg::DetectFeatures(scan, window_->RegistrationOptions().sift);
    QVERIFY(features.ok());
    QVERIFY(features->size() > 100);
    QCOMPARE(view->KeypointMarkerCount(), features->size());
    QCOMPARE(view->InlierLineCount() + view->OutlierLineCount(), 0);
    SaveScreenshot("scan_panorama.png");
  }

  void ConfusionCellOpensThePairWithTheLinksInliers() {
    scanreg::ui::ConfusionPanel* confusion = window_->confusionPanel();
    const QString parent = QString::fromStdString(link_.parent), child = QString::fromStdString(link_.child);
    const int row = RowOf(confusion, child, true), col = RowOf(confusion, parent, false);
    QVERIFY(row >= 0 && col >= 0);
    ClickCell(confusion, row, col);
    // The stored evidence first, without a run (issue 14); Run registers the pair again.
    scanreg::ui::PairPanel* stored = window_->pairInspector()->pairPanel();
    QVERIFY(!window_->jobs()->busy());
    QCOMPARE(stored->Evidence("matches"), QString::number(link_.matches));
    QCOMPARE(stored->Evidence("inliers"), QString::number(link_.ransac_inliers));
    QVERIFY2(stored->Evidence("error").contains("stored"), qPrintable(stored->Evidence("error")));
    QVERIFY(!stored->useButton()->isEnabled());
    QTest::mouseClick(stored->runButton(), Qt::LeftButton);
    QVERIFY(WaitForJob(*window_, 120000));
    scanreg::ui::PanoramaView* view = window_->pairInspector()->panoramaView();
    QCOMPARE(view->ShownScan(), child + " → " + parent);
    // The pair is registered again with the link's method and the same SIFT features: the same
    // SIFT matches, and the lines drawn are the SIFT inliers of the pair's coarse step (its FPFH
    // features come from the pair alone, so their count may differ from the project's link).
    const auto& inspected = window_->pairInspector()->lastPair()->result.link;
    QCOMPARE(view->InlierLineCount(), inspected.ransac_inliers - inspected.geometric_inliers);
    QVERIFY(view->InlierLineCount() > 0);
    QCOMPARE(inspected.status, scanreg::io::LinkStatus::kOk);
    QCOMPARE(view->InlierLineCount() + view->OutlierLineCount(), link_.matches);
    QVERIFY(view->OutlierLineCount() > 0);
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    QCOMPARE(panel->parentScan(), parent);
    QCOMPARE(panel->childScan(), child);
    QCOMPARE(panel->Evidence("inliers"), QString::number(inspected.ransac_inliers));
    QCOMPARE(panel->Evidence("matches"), QString::number(link_.matches));
    // The 3D view shows the overlay (both scans) with its colour scale.
    QCOMPARE(window_->view3d()->PropCount(), 2);
    QCOMPARE(window_->view3d()->renderer()->GetActors2D()->GetNumberOfItems(), 1);
    const auto& pair = *window_->pairInspector()->lastPair();
    QVERIFY(pair.child_points.size() > 1000);
    int near = 0, overlapping = 0;
    for (float d : pair.child_distance_m) {
      overlapping += d >= 0;
      near += d >= 0 && d < 0.03f;  // 12 mm range noise: most overlapping points within 30 mm
    }
    QVERIFY2(overlapping > 0.1 * pair.child_points.size(), qPrintable(QString::number(overlapping)));
    QVERIFY2(near > 0.8 * overlapping, qPrintable(QString("%1 of %2").arg(near).arg(overlapping)));
    SaveScreenshot("pair_inspection.png");
  }

  // Every fine method from the link's coarse method (3d), and EPnP with dense ICP: the panel runs
  // the chosen methods, fills the evidence and shows the error against the reference poses.
  void PairRunsMatchTheReferencePosesWithEveryMethod() {
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    auto* coarse = panel->findChild<QComboBox*>("PairCoarseMethod");
    auto* fine = panel->findChild<QComboBox*>("PairFineMethod");
    QVERIFY(coarse && fine);
    QCOMPARE(fine->count(), static_cast<int>(scanreg::pipeline::AllFineMethods().size()));
    QCOMPARE(coarse->count(), static_cast<int>(scanreg::pipeline::AllCoarseMethods().size()));
    panel->SetPair(QString::fromStdString(link_.parent), QString::fromStdString(link_.child));
    const Eigen::Isometry3d truth = TruePair(window_->project(), link_.parent, link_.child);
    std::vector<std::pair<QString, QString>> runs;
    for (int f = 0; f < fine->count(); ++f) runs.emplace_back("3d", fine->itemText(f));
    runs.emplace_back("epnp", "dense");
    for (const auto& [coarse_name, fine_name] : runs) {
      coarse->setCurrentText(coarse_name);
      fine->setCurrentText(fine_name);
      const QString method = coarse_name + "+" + fine_name;
      QTest::mouseClick(panel->runButton(), Qt::LeftButton);
      QVERIFY2(!panel->runButton()->isEnabled(), "Run is disabled while the pair runs");
      QVERIFY2(WaitForJob(*window_, 120000), qPrintable(method));
      const auto& pair = *window_->pairInspector()->lastPair();
      // "levelled" follows when both scans are levelled (the 4-DoF coarse solver); "plan+" leads when
      // the correspondences did not settle the pose and a plan-view start did.
      const QString got = QString::fromStdString(pair.result.link.method);
      QVERIFY2(got.startsWith(method) || got.startsWith("plan+" + fine_name), qPrintable(got));
      QCOMPARE(panel->Evidence("method"), QString::fromStdString(pair.result.link.method));
      const scanreg::PoseError e = scanreg::ComparePoses(pair.result.link.parent_from_child, truth);
      qInfo("%s: %.2f mm, %.4f deg, %d inliers, RMS %.1f mm, %s", qPrintable(method), 1000 * e.position_m,
            e.angle_rad * 180 / M_PI, pair.result.link.ransac_inliers, 1000 * pair.result.link.rms_m,
            scanreg::io::LinkStatusName(pair.result.link.status));
      // Dense ICP on every surface is sub-millimetre on this pair; every method lands within the
      // coarse stage's reach (the others fit keypoints or range images: 1-3 cm here).
      const bool dense = fine_name == "dense";
      const double max_m = dense ? 0.003 : 0.1, max_deg = dense ? 0.01 : 0.5;
      // Projective ICP (S's baseline) depends on the coarse start more than the others: it must land
      // within reach or say that it failed, never accept a pose off by more.
      const bool may_fail = fine_name == "projective-icp";
      if (!may_fail || pair.result.link.status != scanreg::io::LinkStatus::kFailed) {
        QVERIFY2(e.position_m < max_m, qPrintable(method + QString(": %1 m").arg(e.position_m)));
        QVERIFY2(e.angle_rad < max_deg * M_PI / 180, qPrintable(method + QString(": %1 rad").arg(e.angle_rad)));
      }
      // The panel shows that error and the evidence.
      QVERIFY(pair.reference_error.has_value());
      QVERIFY(std::abs(pair.reference_error->position_m - e.position_m) < 1e-9);
      QVERIFY2(panel->Evidence("error").startsWith(QString::number(1000 * e.position_m, 'f', 1) + " mm"),
               qPrintable(panel->Evidence("error")));
      QVERIFY2(panel->Evidence("status").contains(scanreg::io::LinkStatusName(pair.result.link.status)),
               qPrintable(panel->Evidence("status")));
      QCOMPARE(panel->Evidence("inliers"), QString::number(pair.result.link.ransac_inliers));
      QVERIFY(got.startsWith("plan+") || pair.result.link.ransac_inliers >= 5);  // a plan-view pose has none
      QCOMPARE(panel->Evidence("rms"), QString("%1 mm").arg(1000 * pair.result.link.rms_m, 0, 'f', 1));
      QCOMPARE(panel->Evidence("overlap"), QString("%1 %").arg(100 * pair.result.link.overlap, 0, 'f', 1));
      QVERIFY(pair.result.link.overlap > 0.15);
      QCOMPARE(panel->Evidence("iterations").toInt(), pair.result.link.iterations);
      QVERIFY(panel->Evidence("time").endsWith(" s"));
      if (dense) {
        QCOMPARE(pair.result.link.status, scanreg::io::LinkStatus::kOk);
        QVERIFY(pair.result.link.rms_m > 0.005 && pair.result.link.rms_m < 0.02);  // 12 mm range noise
        QVERIFY(panel->useButton()->isEnabled());
      }
    }
  }

  // Uses the previous test's last run (epnp chosen, dense), a method other than the link's.
  void UsingAPairResultIsAnUndoableEdit() {
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    QVERIFY(window_->pairInspector()->lastPair().has_value());
    QVERIFY(window_->pairInspector()->lastPair()->result.link.method != link_.method);
    const scanreg::io::Project before = window_->project();
    const auto& used = window_->pairInspector()->lastPair()->result.link;
    QVERIFY2(panel->useButton()->isEnabled(), qPrintable(panel->Evidence("status") + " " + panel->Evidence("reason")));
    QTest::mouseClick(panel->useButton(), Qt::LeftButton);
    const scanreg::io::Project& after = window_->project();
    const int p = after.FindScan(link_.parent), c = after.FindScan(link_.child);
    const Eigen::Isometry3d expected = after.scans[p].world_from_scan * used.parent_from_child;
    QVERIFY(after.scans[c].world_from_scan.isApprox(expected, 1e-12));
    int found = 0;
    for (const auto& l : after.links)
      found += l.parent == link_.parent && l.child == link_.child && l.method == used.method;
    QCOMPARE(found, 1);
    QVERIFY(window_->undoStack()->canUndo());
    window_->undoStack()->undo();
    QVERIFY(window_->project().scans[c].world_from_scan.matrix() == before.scans[c].world_from_scan.matrix());
    QCOMPARE(window_->project().links.size(), before.links.size());
  }

  void DoubleClickingANetworkLinkOpensItsPair() {
    scanreg::ui::NetworkPanel* network = window_->networkPanel();
    const QString parent = QString::fromStdString(link_.parent), child = QString::fromStdString(link_.child);
    QGraphicsLineItem* edge = nullptr;
    for (QGraphicsItem* item : network->scene()->items()) {
      auto* line = dynamic_cast<QGraphicsLineItem*>(item);
      if (!line) continue;
      const auto& l = window_->project().links[line->data(0).toInt()];
      if (l.parent == link_.parent && l.child == link_.child && !l.loop_check) edge = line;
    }
    QVERIFY(edge != nullptr);
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    panel->SetPair(child, parent);  // the other way round: the click must set it
    // 4 pixels beside the line still picks it (tolerant picking), at any zoom.
    network->scale(1.6, 1.6);
    network->centerOn(edge->line().center());
    const QPointF centre = network->mapFromScene(edge->line().center());
    const QLineF on_screen(network->mapFromScene(edge->line().p1()), network->mapFromScene(edge->line().p2()));
    const QPointF normal = QPointF(-on_screen.dy(), on_screen.dx()) / on_screen.length();
    const QPoint at = (centre + 4.0 * normal).toPoint();
    const std::vector<int> near = network->LinksNear(at);
    QVERIFY(!near.empty());
    QVERIFY(network->LinksNear(at, 1.0).empty() || network->LinksNear(at, 1.0) != near);
    QTest::mouseDClick(network->viewport(), Qt::LeftButton, {}, at);
    QVERIFY(!window_->jobs()->busy());  // the stored evidence is shown; nothing runs
    QCOMPARE(panel->parentScan(), QString::fromStdString(window_->project().links[near.front()].parent));
    QCOMPARE(panel->childScan(), QString::fromStdString(window_->project().links[near.front()].child));
    const QString tip = network->LinkToolTip(near.front());
    QVERIFY2(tip.contains("matches") && tip.contains("RMS"), qPrintable(tip));
    // Labels keep their screen size when zoomed: readable at any size.
    QGraphicsSimpleTextItem* label = nullptr;
    for (QGraphicsItem* item : network->scene()->items())
      if (auto* t = dynamic_cast<QGraphicsSimpleTextItem*>(item)) label = t;
    QVERIFY(label != nullptr);
    auto on_screen_height = [&] {
      return label->deviceTransform(network->viewportTransform()).mapRect(label->boundingRect()).height();
    };
    const double before = on_screen_height();
    network->scale(3, 3);
    QVERIFY(before > 8);
    QCOMPARE(on_screen_height(), before);
    network->Fit();
  }

  void APairRunRequestedDuringAnotherJobStartsAfterIt() {
    // A scan whose panorama has not been computed yet (s02 and the pair's scans have been).
    QString other;
    for (const auto& s : window_->project().scans)
      if (s.name != link_.parent && s.name != link_.child && s.name != window_->project().scans[1].name) other = s.name.c_str();
    QVERIFY(window_->pairInspector()->ShowScan(other));
    QVERIFY(window_->jobs()->busy());
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    panel->SetPair(QString::fromStdString(link_.parent), QString::fromStdString(link_.child));
    QTest::mouseClick(panel->runButton(), Qt::LeftButton);
    QVERIFY(!panel->runButton()->isEnabled());  // waiting
    QVERIFY(panel->cancelButton()->isEnabled());
    QVERIFY(WaitForJob(*window_, 120000));  // the panorama
    QCOMPARE(window_->pairInspector()->panoramaView()->ShownScan(), other);
    QTRY_VERIFY_WITH_TIMEOUT(window_->jobs()->busy(), 5000);  // then the pair
    QTest::mouseClick(panel->cancelButton(), Qt::LeftButton);
    bool cancelled = false;
    QVERIFY(!WaitForJob(*window_, 120000, &cancelled));
    QVERIFY(cancelled);
    QVERIFY(panel->runButton()->isEnabled());
  }

  void CancellingAPairRunLeavesTheProjectUnchanged() {
    const scanreg::io::Project before = window_->project();
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    panel->SetPair(QString::fromStdString(link_.parent), QString::fromStdString(link_.child));
    QTest::mouseClick(panel->runButton(), Qt::LeftButton);
    QVERIFY(panel->cancelButton()->isEnabled());
    QTest::mouseClick(panel->cancelButton(), Qt::LeftButton);
    bool cancelled = false;
    QVERIFY(!WaitForJob(*window_, 120000, &cancelled));
    QVERIFY(cancelled);
    QCOMPARE(panel->Evidence("status"), QString("cancelled"));
    QVERIFY(!panel->useButton()->isEnabled());
    QVERIFY(panel->runButton()->isEnabled());
    const scanreg::io::Project& after = window_->project();
    QCOMPARE(after.links.size(), before.links.size());
    for (std::size_t i = 0; i < before.links.size(); ++i) {
      QCOMPARE(after.links[i].method, before.links[i].method);
      QVERIFY(after.links[i].parent_from_child.matrix() == before.links[i].parent_from_child.matrix());
    }
    for (std::size_t i = 0; i < before.scans.size(); ++i)
      QVERIFY(after.scans[i].world_from_scan.matrix() == before.scans[i].world_from_scan.matrix());
  }

 private:
  // A screenshot of the window (kept where SCANREG_UI_SCREENSHOT_DIR says, else in the temp dir).
  void SaveScreenshot(const QString& name) {
    const QString path = qEnvironmentVariable("SCANREG_UI_SCREENSHOT_DIR", dir_.path()) + "/" + name;
    QTest::qWait(300);
    QVERIFY(window_->SaveScreenshot(path));
    QCOMPARE(QImage(path).size(), window_->size());
  }

  QTemporaryDir dir_;
  MainWindow* window_ = nullptr;
  scanreg::io::LinkRecord link_;
};

int main(int argc, char** argv) {
  QSurfaceFormat::setDefaultFormat(QVTKOpenGLNativeWidget::defaultFormat());
  QApplication app(argc, argv);
  PairInspectorTest test;
  return QTest::qExec(&test, argc, argv);
}

#include "pair_inspector_test.moc"
