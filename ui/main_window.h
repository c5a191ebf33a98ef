// The scanreg main window: project menus, the 3D view, dock panels (scans, confusion matrix,
// log) and a status bar with the running job's progress and a Cancel button. Long jobs (load,
// demo, registration) run on the JobRunner; results come back by value.
#pragma once

#include <Eigen/Core>
#include <QMainWindow>
#include <any>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"

class QAction;
class QProgressBar;
class QPushButton;
class QUndoStack;

namespace scanreg::ui {

class ConfusionPanel;
class JobRunner;
class LogPanel;
class NetworkPanel;
class PairInspector;
class ScanListPanel;
class View3d;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  // Start jobs (return false while another job runs). Completion: jobs()->Succeeded / Failed.
  bool OpenProject(const QString& path);
  bool OpenDemoProject(const QString& dir);  // simulates a small street project into dir
  bool RegisterProject();
  bool SaveProject(const QString& path);  // synchronous, atomic
  // The options of the project's registration (also the pair panel's starting point).
  pipeline::RegisterOptions RegistrationOptions() const;
  // Applies a pair registration (the pair panel's "Use this result") as an undoable edit; false,
  // with a dialog naming the scans, when it cannot be applied.
  bool UsePairResult(const io::LinkRecord& link);
  // Redraws the panels and the 3D view from the project.
  void Refresh();

  // The user's edits, undoable. A parent override re-runs the registration when no job runs.
  void SetParentOverride(const QString& child, const QString& parent);  // parent empty: clear
  void SetLinkDecision(const QString& parent, const QString& child, bool accept, bool reject);
  QUndoStack* undoStack() const { return undo_; }
  // Replaces the project with an edited version (used by the undo commands).
  void ApplyEdit(const io::Project& project, bool rerun);

  JobRunner* jobs() const { return jobs_; }
  View3d* view3d() const { return view3d_; }
  const io::Project& project() const { return project_; }
  const std::vector<Scan>& scans() const { return scans_; }
  const Eigen::MatrixXi& confusion() const { return confusion_; }
  ScanListPanel* scanList() const { return scan_list_; }
  ConfusionPanel* confusionPanel() const { return confusion_panel_; }
  NetworkPanel* networkPanel() const { return network_; }
  PairInspector* pairInspector() const { return inspector_; }
  bool dirty() const { return dirty_; }

  // Renders the window (including the VTK view) into a PNG; returns false on failure.
  bool SaveScreenshot(const QString& path);

 signals:
  void ProjectChanged();  // the panels were redrawn from the project (emitted by Refresh)

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void CreateMenus();
  void CreateDocks();
  void OnJobSucceeded(const QString& title, std::any result);
  void OnJobFailed(const QString& title, const QString& message, bool cancelled);
  void SetBusy(bool busy);
  void ShowError(const QString& title, const QString& message);
  void ShowAbout();

  io::Project project_;
  std::vector<Scan> scans_;
  Eigen::MatrixXi confusion_;
  bool dirty_ = false;
  bool colour_by_reflectance_ = false;

  JobRunner* jobs_ = nullptr;
  View3d* view3d_ = nullptr;
  ScanListPanel* scan_list_ = nullptr;
  ConfusionPanel* confusion_panel_ = nullptr;
  LogPanel* log_ = nullptr;
  NetworkPanel* network_ = nullptr;
  PairInspector* inspector_ = nullptr;
  QUndoStack* undo_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QPushButton* cancel_ = nullptr;
  std::vector<QAction*> project_actions_;  // enabled only with a project and no job
};

}  // namespace scanreg::ui
