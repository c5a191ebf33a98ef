// Wires the panorama view and the pair panel to the main window: selecting a scan in the scan
// list shows its panorama; clicking a confusion-matrix cell, double-clicking a link of the scan
// network or the pair panel's Run registers that pair on the worker and shows both panoramas with
// the inlier / outlier matches, the evidence in the pair panel and both scans in the 3D view
// coloured by their distance to each other. Jobs run on the window's JobRunner (progress and
// Cancel in the status bar); a request made while another job runs starts when it ends.
#pragma once

#include <QObject>
#include <QString>
#include <functional>
#include <map>
#include <optional>

#include "core/pipeline/inspect_pair.h"
#include "ui/job_runner.h"
#include "ui/panorama_view.h"

class QDockWidget;

namespace scanreg::ui {

class MainWindow;
class PairPanel;

class PairInspector : public QObject {
  Q_OBJECT

 public:
  // Creates the panorama view and the pair panel as docks of the window.
  explicit PairInspector(MainWindow* window);

  PanoramaView* panoramaView() const { return panorama_; }
  PairPanel* pairPanel() const { return panel_; }
  // The last pair run that succeeded (its evidence is in the pair panel); none after a reload.
  const std::optional<pipeline::PairInspection>& lastPair() const { return last_pair_; }

  // Each returns false when the request is not possible (unknown scan, no project); a request
  // made while a job runs is queued (the latest wins) and returns true.
  bool ShowScan(const QString& name);
  // Selects the pair in the panel (with the link's methods when the project has that link) and runs it.
  bool OpenPair(const QString& parent, const QString& child);
  bool RunPair();  // the panel's pair and methods
  void CancelPair();

 private:
  void OnProjectOpened();   // another project: what was computed belongs to the old one
  void OnProjectChanged();  // the scan names offered in the pair panel
  void OnJobSucceeded(const QString& title);
  void OnJobFailed(const QString& title, const QString& message, bool cancelled);
  // Starts now, or keeps the request in *slot until the running job ends (the latest wins).
  void StartOrQueue(std::function<bool()>* slot, std::function<bool()> start);
  void StartQueued();  // after a job: the waiting pair first, else the waiting panorama
  template <typename T>
  bool Start(const QString& title, JobRunner::Job<T> job, JobRunner::Done<T> done);
  void ShowOverlay();
  void GrowPanoramaDockOnce();
  void UseResult();

  MainWindow* window_;
  PanoramaView* panorama_ = nullptr;
  PairPanel* panel_ = nullptr;
  QDockWidget* pano_dock_ = nullptr;
  bool grew_panorama_ = false;
  std::map<QString, PanoramaImage> panoramas_;  // computed panoramas by scan name (this project)
  std::optional<pipeline::PairInspection> last_pair_;
  QString running_;  // title of this inspector's running job
  std::function<bool()> queued_pair_, queued_scan_;
};

}  // namespace scanreg::ui
