// Drives the panorama view, the confusion matrix and the pair panel of the real main window under
// Xvfb, on the simulated demo project (5 stations with known poses), registered once.
#include <QComboBox>
#include <QElapsedTimer>
#include <QPushButton>
#include <QSignalSpy>
#include <QSurfaceFormat>
#include <QTemporaryDir>
#include <QUndoStack>
#include <QVTKOpenGLNativeWidget.h>
#include <QtTest/QtTest>
#include <cmath>
#include <vtkActor2DCollection.h>
#include <vtkRenderer.h>

#include "core/features/sift.h"
#include "core/geometry/transform.h"
#include "tests/ui/wait_for_job.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/pair_inspector.h"
#include "ui/pair_panel.h"
#include "ui/panorama_view.h"
#include "ui/project_panels.h"
#include "ui/view_3d.h"

using scanreg::ui::JobRunner;
using scanreg::test::WaitForJob;
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
      if (!l.loop_check && l.status == scanreg::io::LinkStatus::kOk && l.ransac_inliers > link_.ransac_inliers) link_ = l;
    QVERIFY2(!link_.parent.empty(), "the demo registration has an ok link");
  }

  void cleanupTestCase() { delete window_; }

  void SelectingAScanShowsItsPanoramaWithItsKeypoints() {
    const int row = 1;
    const scanreg::Scan& scan = window_->scans()[row];
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
  }

  void ConfusionCellOpensThePairWithTheLinksInliers() {
    scanreg::ui::ConfusionPanel* confusion = window_->confusionPanel();
    const QString parent = QString::fromStdString(link_.parent), child = QString::fromStdString(link_.child);
    const int row = RowOf(confusion, child, true), col = RowOf(confusion, parent, false);
    QVERIFY(row >= 0 && col >= 0);
    ClickCell(confusion, row, col);
    QVERIFY(WaitForJob(*window_, 120000));
    scanreg::ui::PanoramaView* view = window_->pairInspector()->panoramaView();
    QCOMPARE(view->ShownScan(), child + " → " + parent);
    // The pair is registered again with the link's method and the same features: the same inliers.
    QCOMPARE(view->InlierLineCount(), link_.ransac_inliers);
    QCOMPARE(view->InlierLineCount() + view->OutlierLineCount(), link_.matches);
    QVERIFY(view->OutlierLineCount() > 0);
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    QCOMPARE(panel->parentScan(), parent);
    QCOMPARE(panel->childScan(), child);
    QCOMPARE(panel->Evidence("inliers"), QString::number(link_.ransac_inliers));
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
  }

  void PairRunsMatchTheReferencePosesWithEveryMethod() {
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    auto* coarse = panel->findChild<QComboBox*>("PairCoarseMethod");
    auto* fine = panel->findChild<QComboBox*>("PairFineMethod");
    QVERIFY(coarse && fine);
    QCOMPARE(fine->count(), static_cast<int>(scanreg::pipeline::AllFineMethods().size()));
    panel->SetPair(QString::fromStdString(link_.parent), QString::fromStdString(link_.child));
    const Eigen::Isometry3d truth = TruePair(window_->project(), link_.parent, link_.child);
    for (int c = 0; c < coarse->count(); ++c) {
      for (int f = 0; f < fine->count(); ++f) {
        coarse->setCurrentIndex(c);
        fine->setCurrentIndex(f);
        const QString method = coarse->currentText() + "+" + fine->currentText();
        QTest::mouseClick(panel->runButton(), Qt::LeftButton);
        QVERIFY2(!panel->runButton()->isEnabled(), "Run is disabled while the pair runs");
        QVERIFY2(WaitForJob(*window_, 120000), qPrintable(method));
        const auto& pair = *window_->pairInspector()->lastPair();
        QCOMPARE(QString::fromStdString(pair.result.link.method), method);
        QCOMPARE(QString::fromStdString(pair.result.link.method), panel->Evidence("method"));
        const scanreg::PoseError e = scanreg::ComparePoses(pair.result.link.parent_from_child, truth);
        qInfo("%s: %.2f mm, %.4f deg, %d inliers, RMS %.1f mm", qPrintable(method), 1000 * e.position_m,
              e.angle_rad * 180 / M_PI, pair.result.link.ransac_inliers, 1000 * pair.result.link.rms_m);
        // Dense ICP uses every surface (sub-mm on this pair); the other methods fit the few
        // keypoint pairs (21 coarse inliers here, 12 mm range noise): a few mm.
        const bool dense = fine->currentText() == "dense";
        const double max_m = dense ? 0.003 : 0.015, max_deg = dense ? 0.01 : 0.15;
        QVERIFY2(e.position_m < max_m, qPrintable(method + QString(": %1 m").arg(e.position_m)));
        QVERIFY2(e.angle_rad < max_deg * M_PI / 180, qPrintable(method + QString(": %1 rad").arg(e.angle_rad)));
        // The panel shows the same error and the evidence.
        QVERIFY(pair.reference_error.has_value());
        QVERIFY(std::abs(pair.reference_error->position_m - e.position_m) < 1e-9);
        QVERIFY2(panel->Evidence("error").startsWith(QString::number(1000 * e.position_m, 'f', 1) + " mm"),
                 qPrintable(panel->Evidence("error")));
        QVERIFY2(panel->Evidence("status").contains(">ok<"), qPrintable(panel->Evidence("status")));
        QCOMPARE(panel->Evidence("inliers"), QString::number(pair.result.link.ransac_inliers));
        QVERIFY(pair.result.link.ransac_inliers >= 8);
        QVERIFY(pair.result.link.overlap > 0.15 && panel->Evidence("overlap").endsWith(" %"));
        QVERIFY(pair.result.link.rms_m > 0.002 && pair.result.link.rms_m < 0.04);
        QVERIFY(pair.result.link.iterations > 0 && panel->Evidence("iterations").toInt() == pair.result.link.iterations);
        QVERIFY(panel->Evidence("time").endsWith(" s"));
        QVERIFY(panel->useButton()->isEnabled());
      }
    }
  }

  void UsingAPairResultIsAnUndoableEdit() {
    scanreg::ui::PairPanel* panel = window_->pairInspector()->pairPanel();
    panel->SetPair(QString::fromStdString(link_.parent), QString::fromStdString(link_.child));
    panel->SetMethods(scanreg::CoarseMethod::kEpnp, scanreg::pipeline::FineMethod::kKeypoints);
    QTest::mouseClick(panel->runButton(), Qt::LeftButton);
    QVERIFY(WaitForJob(*window_, 120000));
    const scanreg::io::Project before = window_->project();
    const auto& used = window_->pairInspector()->lastPair()->result.link;
    QVERIFY2(panel->useButton()->isEnabled(), qPrintable(panel->Evidence("status") + " " + panel->Evidence("reason")));
    QTest::mouseClick(panel->useButton(), Qt::LeftButton);
    const scanreg::io::Project& after = window_->project();
    const int p = after.FindScan(link_.parent), c = after.FindScan(link_.child);
    const Eigen::Isometry3d expected = after.scans[p].world_from_scan * used.parent_from_child;
    QVERIFY(after.scans[c].world_from_scan.isApprox(expected, 1e-12));
    int found = 0;
    for (const auto& l : after.links) found += l.parent == link_.parent && l.child == link_.child && l.method == "epnp+keypoints";
    QCOMPARE(found, 1);
    QVERIFY(window_->undoStack()->canUndo());
    window_->undoStack()->undo();
    QVERIFY(window_->project().scans[c].world_from_scan.matrix() == before.scans[c].world_from_scan.matrix());
    QCOMPARE(window_->project().links.size(), before.links.size());
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
