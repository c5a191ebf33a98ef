// scanreg --screenshots DIR: opens the demo project, registers it, merges it and saves a PNG of
// each main view. To add a view, add an entry to ScreenshotViews(); its `prepare` may start jobs
// (the tour grabs once the worker is idle).
#pragma once

#include <QImage>
#include <QObject>
#include <QString>
#include <functional>
#include <vector>

#include "core/merge/merge_options.h"

class QDockWidget;

namespace scanreg::ui {

class MainWindow;

struct ScreenshotView {
  QString file;  // PNG file name, e.g. "scan_network.png"
  // The dock shown on its own (floated at kPanelSize) while it is grabbed; empty for none.
  QString dock;
  std::function<void(MainWindow&)> prepare;  // e.g. show the mesh only; may be empty
  std::function<QImage(MainWindow&)> grab;
};

std::vector<ScreenshotView> ScreenshotViews();

class ScreenshotTour : public QObject {
  Q_OBJECT

 public:
  static constexpr int kPanelWidth = 900, kPanelHeight = 640, kRightDockWidth = 560;

  // As the CLI demo: TSDF, 10 cm voxels, returns within 25 m.
  static merge::MergeOptions DemoMerge();

  // Writes the PNGs into dir; the mesh is merged with `merge`.
  ScreenshotTour(MainWindow* window, QString dir, merge::MergeOptions merge = DemoMerge());
  // Simulates the demo project into demo_dir; or opens a project (registered unless it is already).
  void StartDemo(const QString& demo_dir);
  void Start(const QString& project);

 signals:
  void Finished(bool ok, const QString& message);

 private:
  void OnJobDone(const QString& title, bool ok, const QString& message);
  void ShootNext();
  void Grab(QDockWidget* dock, int idle_checks);

  MainWindow* window_;
  bool Prepare();
  QString dir_;
  merge::MergeOptions merge_;
  enum class Stage { kLoading, kRegistering, kMerging, kShooting, kDone } stage_ = Stage::kLoading;
  std::vector<ScreenshotView> views_;
  std::size_t next_ = 0;
  QStringList written_;
};

}  // namespace scanreg::ui
