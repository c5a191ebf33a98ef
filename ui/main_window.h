// The scanreg main window: project menus, the 3D view, dock panels (scans, confusion matrix,
// log) and a status bar with the running job's progress and a Cancel button. The open project is
// a ProjectDocument the panels observe; long jobs (load, demo, registration) run on the JobRunner
// and hand their typed results to the document.
#pragma once

#include <Eigen/Core>
#include <QImage>
#include <QMainWindow>
#include <functional>
#include <vector>

#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/scan_previews.h"

class QAction;
class QMenu;
class QProgressBar;
class QPushButton;
class QUndoStack;

namespace scanreg::ui {

class ConfusionPanel;
class JobRunner;
class LogPanel;
class MergePanel;
class PickPointsDialog;
class PickTargetDialog;
class PoseDialog;
class ProjectDocument;
class RegisterSettingsDialog;
class NetworkPanel;
class PairInspector;
class ScanListPanel;
class ControlPanel;
class ScanScene;
class View3d;

class MainWindow : public QMainWindow {
  Q_OBJECT

 public:
  explicit MainWindow(QWidget* parent = nullptr);
  ~MainWindow() override;

  // Start jobs (return false while another job runs). Completion: jobs()->Succeeded / Failed; the
  // result is in document() by then.
  // Scan files not where the project says are looked for in scan_folder (by file name); those still
  // missing are listed in a dialog that asks for the folder (and opens again with it).
  bool OpenProject(const QString& path, const QString& scan_folder = QString());
  bool OpenDemoProject(const QString& dir);  // simulates a small street project into dir
  bool RegisterProject();
  // Synchronous and atomic, under the project's lock; a project changed on disk since it was read
  // is not overwritten: a dialog offers to reload it or save under another name.
  bool SaveProject(const QString& path);
  void SaveProjectAs();  // asks for the file; adds .scanreg.json when the name has no .json
  // The options of the project's registration (also the pair panel's starting point).
  pipeline::RegisterOptions RegistrationOptions() const;
  // The options stored in the project's settings as an undoable edit (false when nothing changed).
  bool SetRegisterOptions(const pipeline::RegisterOptions& options);
  // Registration → Settings…: the dialog (window-modal, does not block), for tests.
  RegisterSettingsDialog* EditRegisterSettings();
  // Applies a pair registration (the pair panel's "Use this result") as an undoable edit; false,
  // with a dialog naming the scans, when it cannot be applied.
  bool UsePairResult(const io::LinkRecord& link);
  // Redraws the panels and the 3D view from the document (on its Changed signal).
  void Refresh();
  // A new project from scan files (io::SupportedScanExtensions()), saved at project_path; and
  // scans added to the open project (unsaved until Save). Both read the files on the worker.
  bool NewProject(const QStringList& scan_files, const QString& project_path);
  bool AddScans(const QStringList& scan_files);
  // Project management (issue 14, item 6), undoable; false with a dialog when refused. Removing a
  // scan keeps the poses of the scans registered through it (the status bar names them).
  bool RemoveScan(const QString& scan);
  bool RenameScan(const QString& scan, const QString& new_name);
  bool SetRoot(const QString& scan);
  // File → Import control points… (issue 15): the file's points replace the project's control, as
  // an undoable edit; the next registration places the project on them. False, with a dialog
  // naming the file and line, when it cannot be read.
  bool ImportControl(const QString& path);
  // Registration → Pick a target in scan…: the dialog for the scan (window-modal, does not block;
  // null with a dialog when the scan is unknown). Accepting it calls AddPickedTarget.
  PickTargetDialog* PickTarget(const QString& scan);
  // The picked target joins the project (pipeline::AddPickedTarget, undoable); the next
  // georeferencing uses it. False, with a dialog, when refused.
  bool AddPickedTarget(const io::TargetRecord& target);
  // Registration → Georeference on control: the registered project placed on its control points
  // from its targets (pipeline::GeoreferenceProject) on the worker, without registering again;
  // the result is an undoable edit, or a dialog says why it could not be placed.
  bool Georeference();
  // Points the scan at another file (read on the worker; refused when it holds another grid).
  bool RelinkScan(const QString& scan, const QString& file);
  // Writes the registration report (dir/index.html and its pictures) on the worker.
  bool ExportReport(const QString& dir);
  // With unsaved changes, asks whether to save them; false when the user cancels (or saving failed).
  bool MaybeSaveChanges();
  // A dialog naming the problem and the next step (window-modal, does not block); also logged.
  void ShowError(const QString& title, const QString& message);
  void OfferReload(const QString& path, const QString& message);

  // The user's edits, undoable. A parent override registers the child to that parent on the
  // worker (pipeline::OverrideParent: only it and the scans under it); when that link fails the old
  // one stays and a dialog says why. False when a job runs or the names are wrong.
  bool SetParentOverride(const QString& child, const QString& parent);  // parent empty: clear
  void SetLinkDecision(const QString& parent, const QString& child, bool accept, bool reject);
  // Places a scan by hand (pipeline::SetScanPose); false, with a dialog, when refused.
  bool SetScanPose(const QString& scan, const Eigen::Isometry3d& world_from_scan, bool move_dependents);
  // Lets the registration place a scan placed by hand (Register all keeps hand placements); false,
  // with a dialog, when the scan was not placed by hand.
  bool ReleaseHandPlacement(const QString& scan);
  // The scan selected in the scan list (empty when none).
  QString SelectedScan() const;
  // Registration → Register unregistered scans: only the scans that are not registered are placed;
  // the others keep their poses and links. False when every scan is registered or a job runs.
  bool RegisterUnregistered();
  // Registration → Refine all from current poses: one run of --coarse none (the saved settings are
  // not changed).
  bool RefineFromCurrentPoses();
  // Registration → Refine scan from its pose (and the pair panel's Refine from current poses): the
  // scan refined against `parent` (default: its tree parent, else the nearest registered scan) from
  // where both stand; the result becomes its link (undoable), or a dialog says why it failed.
  bool RefineScan(const QString& scan, const QString& parent = QString());
  // Registration → Align by picked points…: the dialog for `child` (window-modal, does not block;
  // null with a dialog when no registered scan can be its parent). Accepting it starts
  // AlignFromPickedPoints.
  PickPointsDialog* PickPoints(const QString& child);
  // Fit and refine on the worker (pipeline::AlignFromPickedPoints); the result becomes the child's
  // link, marked "picked", or a dialog says why not.
  bool AlignFromPickedPoints(const QString& parent, const QString& child, std::vector<io::PickedPoint> pairs,
                             bool levelled);
  // Registration → Edit scan pose…: opens the pose dialog for the scan selected in the scan list
  // (window-modal, does not block); returns it (null when no scan is selected), for tests.
  PoseDialog* EditSelectedScanPose();

  JobRunner* jobs() const { return jobs_; }
  View3d* view3d() const { return view3d_; }
  ProjectDocument* document() const { return doc_; }
  const io::Project& project() const;
  // What the views draw of each scan (the full points: document()->FullScans() / ReadScan()).
  const std::vector<pipeline::ScanPreview>& previews() const;
  const Eigen::MatrixXi& confusion() const;
  QUndoStack* undoStack() const;
  bool dirty() const;
  ScanListPanel* scanList() const { return scan_list_; }
  ConfusionPanel* confusionPanel() const { return confusion_panel_; }
  NetworkPanel* networkPanel() const { return network_; }
  PairInspector* pairInspector() const { return inspector_; }
  ScanScene* scene() const { return scene_; }
  MergePanel* mergePanel() const { return merge_panel_; }

  // A dock's content in a scroll area: a tall panel (pair evidence, merge options) scrolls instead
  // of setting the window's minimum height (the window fits 1366 x 768).
  static QWidget* Scrollable(QWidget* content);

  // The window as shown, including the VTK view's frame (null on failure); and saved as a PNG.
  QImage Screenshot();
  bool SaveScreenshot(const QString& path);

 protected:
  void closeEvent(QCloseEvent* event) override;

 private:
  void CreateMenus();
  void CreateViewMenu();  // camera, colouring, resolution
  void CreateDocks();
  void OnProjectLoaded(io::Project project, std::vector<pipeline::ScanPreview> previews);  // opened, created or simulated
  void UpdateTitle();
  void ShowSkippedFiles(const std::vector<std::string>& skipped);  // batch add: the files left out, and why
  void ReportRegistration();  // the run's summary: log, and the status bar until the next job
  bool StartRegistration(const QString& text, pipeline::RegisterOptions options, bool store_settings);
  // Runs a pair result job and makes its link the child's (Refine scan, picked points).
  bool StartPairJob(const QString& title, std::function<Expected<io::LinkRecord>(ProgressSink&, const CancelToken&)> job);
  void OnJobFailed(const QString& title, const QString& message, bool cancelled);
  void SetBusy(bool busy);
  void ShowAbout();
  void FillRecentMenu(QMenu* menu);

  ProjectDocument* doc_ = nullptr;
  QString last_summary_;  // of the job that just ended
  JobRunner* jobs_ = nullptr;
  View3d* view3d_ = nullptr;
  ScanListPanel* scan_list_ = nullptr;
  ControlPanel* control_panel_ = nullptr;
  ConfusionPanel* confusion_panel_ = nullptr;
  LogPanel* log_ = nullptr;
  NetworkPanel* network_ = nullptr;
  PairInspector* inspector_ = nullptr;
  ScanScene* scene_ = nullptr;
  MergePanel* merge_panel_ = nullptr;
  QProgressBar* progress_ = nullptr;
  QPushButton* cancel_ = nullptr;
  std::vector<QAction*> project_actions_;  // enabled only with a project and no job
};

}  // namespace scanreg::ui
