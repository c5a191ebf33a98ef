#include "ui/main_window.h"

#include <QVTKOpenGLNativeWidget.h>
#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDockWidget>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QPainter>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QScreen>
#include <QSettings>
#include <QShortcut>
#include <QStandardPaths>
#include <QStatusBar>
#include <QTimer>
#include <QUndoStack>

#include "core/common/log.h"
#include "core/io/project_lock.h"
#include "core/io/project_tree.h"
#include "core/io/scan_file.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/register_settings.h"
#include "core/report/report.h"
#include "ui/app_settings.h"
#include "ui/control_panel.h"
#include "ui/job_runner.h"
#include "ui/merge_panel.h"
#include "ui/network_panel.h"
#include "ui/pair_inspector.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"
#include "ui/register_settings_dialog.h"
#include "ui/scan_cloud_actors.h"
#include "ui/scan_scene.h"
#include "ui/view_3d.h"

namespace scanreg::ui {
namespace {

struct LoadedProject {
  io::Project project;
  std::vector<pipeline::ScanPreview> previews;
};

// Scans read for the open project (Add scans): the project with them appended, and their previews.
struct AddedScans {
  io::Project project;
  std::vector<pipeline::ScanPreview> previews;
  std::vector<std::string> skipped;  // why each file left out was left out
};

struct Registered {
  io::Project project;
  Eigen::MatrixXi confusion;
};

// The project's previews, one scan in memory at a time (issue 13: the desktop keeps previews).
// preview_cells: what all previews share.
Expected<LoadedProject> LoadJob(io::Project project, std::size_t preview_cells, ProgressSink& progress,
                                const CancelToken& cancel) {
  Expected<std::vector<pipeline::ScanPreview>> previews = pipeline::LoadScanPreviews(
      project, pipeline::PreviewCellsPerScan(project.scans.size(), preview_cells), progress, cancel);
  if (!previews) return previews.error();
  return LoadedProject{std::move(project), std::move(*previews)};
}

}  // namespace

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(tr("scanreg — terrestrial laser scan registration"));
  setObjectName("MainWindow");
  jobs_ = new JobRunner(this);
  doc_ = new ProjectDocument(this);
  connect(doc_, &ProjectDocument::Changed, this, &MainWindow::Refresh);
  connect(doc_, &ProjectDocument::Opened, this, [this] {
    scene_->ScansReplaced(true);
    log_->clear();  // the log belongs to a project
    log_->Header(tr("Project %1 (%n scan(s))", "", int(project().scans.size()))
                     .arg(QString::fromStdString(project().file.string())));
  });
  connect(doc_, &ProjectDocument::ScansChanged, this, [this] { scene_->ScansReplaced(false); });
  connect(doc_, &ProjectDocument::DirtyChanged, this, &MainWindow::UpdateTitle);
  connect(doc_, &ProjectDocument::RerunRequested, this, [this] {
    if (!jobs_->busy()) RegisterProject();
  });
  view3d_ = new View3d(this);
  view3d_->setObjectName("View3d");
  setCentralWidget(view3d_);
  scene_ = new ScanScene(view3d_, this);
  scene_->SetColouring(QSettings().value("view/colour_by_reflectance").toBool() ? CloudColouring::kReflectance
                                                                                : CloudColouring::kPerScan);
  CreateDocks();
  CreateMenus();

  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setMaximumWidth(260);
  progress_->hide();
  cancel_ = new QPushButton(tr("Cancel"), this);
  cancel_->setObjectName("CancelButton");
  cancel_->hide();
  statusBar()->addPermanentWidget(progress_);
  statusBar()->addPermanentWidget(cancel_);
  connect(cancel_, &QPushButton::clicked, jobs_, &JobRunner::Cancel);
  cancel_->setToolTip(tr("Cancel the running job (Esc)"));
  auto* escape = new QShortcut(QKeySequence(Qt::Key_Escape), this);
  escape->setObjectName("CancelShortcut");
  connect(escape, &QShortcut::activated, jobs_, [this] {
    if (!jobs_->busy()) return;
    jobs_->Cancel();
    statusBar()->showMessage(tr("Cancelling…"));
  });
  connect(jobs_, &JobRunner::Started, this, [this](const QString& title) {
    log_->Header(title);
    SetBusy(true);
    statusBar()->showMessage(title + "…");
  });
  connect(jobs_, &JobRunner::Progress, this, [this](double f, const QString& stage) {
    progress_->setValue(static_cast<int>(f * 1000));
    statusBar()->showMessage(stage);
  });
  connect(jobs_, &JobRunner::Succeeded, this, [this](const QString& title) {
    SetBusy(false);
    // The run's summary when it has one (kept until the next job), else a short "done".
    if (!last_summary_.isEmpty()) {
      statusBar()->showMessage(last_summary_);
    } else {
      statusBar()->showMessage(title + tr(": done"), 5000);
    }
    last_summary_.clear();
  });
  connect(jobs_, &JobRunner::Failed, this, &MainWindow::OnJobFailed);
  inspector_ = new PairInspector(this);  // after the window's own job connections

  // Core log messages arrive on any thread: forward them queued to the log panel.
  // The handler is removed in the destructor (under the log's mutex) before the panel dies, and a
  // queued call to a deleted context object is dropped by Qt.
  LogPanel* log = log_;
  SetLogHandler([log](LogLevel level, const std::string& message) {
    const QString lvl = level == LogLevel::kError ? "error" : level == LogLevel::kWarning ? "warning" : "info";
    const QString text = QString::fromStdString(message);
    QMetaObject::invokeMethod(
        log, [log, lvl, text] { log->Append(lvl, text); }, Qt::QueuedConnection);
  });

  statusBar()->showMessage(tr("No project open."));
  // 1400 x 900, or less on a smaller screen (a 1366 x 768 laptop): never larger than it.
  const QScreen* screen = QGuiApplication::primaryScreen();
  resize(screen ? QSize(1400, 900).boundedTo(screen->availableSize()) : QSize(1400, 900));
  QSettings settings;
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
  SetBusy(false);
}

MainWindow::~MainWindow() { SetLogHandler({}); }

const io::Project& MainWindow::project() const { return doc_->project(); }
const std::vector<pipeline::ScanPreview>& MainWindow::previews() const { return doc_->previews(); }
const Eigen::MatrixXi& MainWindow::confusion() const { return doc_->confusion(); }
QUndoStack* MainWindow::undoStack() const { return doc_->undoStack(); }
bool MainWindow::dirty() const { return doc_->dirty(); }

void MainWindow::CreateDocks() {
  scan_list_ = new ScanListPanel(this);
  confusion_panel_ = new ConfusionPanel(this);
  network_ = new NetworkPanel(this);
  log_ = new LogPanel(this);
  control_panel_ = new ControlPanel(this);
  merge_panel_ = new MergePanel(this, scene_);
  connect(scan_list_, &ScanListPanel::ScanVisibilityChanged, scene_, &ScanScene::SetScanVisible);
  connect(network_, &NetworkPanel::ParentOverrideRequested, this, &MainWindow::SetParentOverride);
  connect(network_, &NetworkPanel::LinkDecisionRequested, this, &MainWindow::SetLinkDecision);
  const std::pair<QWidget*, QString> docks[] = {{scan_list_, tr("Scans")},
                                                {network_, tr("Scan network")},
                                                {confusion_panel_, tr("Confusion matrix")},
                                                {merge_panel_, tr("Merge")},
                                                {control_panel_, tr("Control")},
                                                {log_, tr("Log")}};
  QDockWidget* first_right = nullptr;
  for (const auto& [widget, title] : docks) {
    auto* dock = new QDockWidget(title, this);
    dock->setObjectName(widget->objectName() + "Dock");
    dock->setWidget(widget == merge_panel_ ? Scrollable(widget) : widget);
    addDockWidget(widget == log_ ? Qt::BottomDockWidgetArea : Qt::RightDockWidgetArea, dock);
    if (widget == merge_panel_ || widget == control_panel_) tabifyDockWidget(first_right, dock);  // tabs beside the scan list
    if (widget == merge_panel_) connect(dock, &QDockWidget::visibilityChanged, merge_panel_, &MergePanel::SetShown);
    if (!first_right && widget != log_) first_right = dock;
  }
  first_right->raise();
}

void MainWindow::CreateMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->setObjectName("FileMenu");
  // "*.ptx *.e57 *.ply *.pcd *.las" from io::SupportedScanExtensions() (".ptx, .e57, .ply, .pcd, .las").
  const QString scan_filter =
      tr("Scans (%1);;All files (*)").arg(QString(io::SupportedScanExtensions()).replace(".", "*.").replace(",", ""));
  QAction* create = file->addAction(tr("&New project…"), this, [this, scan_filter] {
    if (!MaybeSaveChanges()) return;
    const QStringList files =
        QFileDialog::getOpenFileNames(this, tr("New project: choose the scans"), LastDir(), scan_filter);
    if (files.isEmpty()) return;
    RememberDir(files.first());
    const QString path =
        QFileDialog::getSaveFileName(this, tr("New project: save it as"), LastDir() + "/project.scanreg.json",
                                     tr("scanreg projects (*.scanreg.json)"));
    if (!path.isEmpty()) NewProject(files, path);
  });
  create->setShortcut(QKeySequence::New);
  QAction* open = file->addAction(tr("&Open project…"), this, [this] {
    if (!MaybeSaveChanges()) return;
    const QString path = QFileDialog::getOpenFileName(this, tr("Open project"), LastDir(),
                                                      tr("scanreg projects (*.scanreg.json);;All files (*)"));
    if (path.isEmpty()) return;
    RememberDir(path);
    OpenProject(path);
  });
  open->setShortcut(QKeySequence::Open);
  QMenu* recent = file->addMenu(tr("Open &recent"));
  recent->setObjectName("RecentMenu");
  connect(recent, &QMenu::aboutToShow, this, [this, recent] { FillRecentMenu(recent); });
  file->addAction(tr("Open &demo project"), this, [this] {
    if (!MaybeSaveChanges()) return;
    const QString dir = QStandardPaths::writableLocation(QStandardPaths::TempLocation) + "/scanreg-demo";
    OpenDemoProject(dir);
  });
  QAction* add = file->addAction(tr("&Add scans…"), this, [this, scan_filter] {
    const QStringList files = QFileDialog::getOpenFileNames(this, tr("Add scans"), LastDir(), scan_filter);
    if (files.isEmpty()) return;
    RememberDir(files.first());
    AddScans(files);
  });
  QAction* control = file->addAction(tr("Import &control points…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Import control points"), LastDir(),
                                                      tr("Control points (*.csv *.txt);;All files (*)"));
    if (path.isEmpty()) return;
    RememberDir(path);
    ImportControl(path);
  });
  control->setObjectName("ImportControlAction");
  QAction* save = file->addAction(tr("&Save project"), this, [this] {
    if (project().file.empty()) {
      SaveProjectAs();
    } else {
      SaveProject(QString::fromStdString(project().file.string()));
    }
  });
  save->setShortcut(QKeySequence::Save);
  QAction* save_as = file->addAction(tr("Save project &as…"), this, &MainWindow::SaveProjectAs);
  QAction* report = file->addAction(tr("Export &report…"), this, [this] {
    const QString dir = QFileDialog::getExistingDirectory(this, tr("Export report into folder"), LastDir());
    if (dir.isEmpty()) return;
    RememberDir(dir);
    ExportReport(dir);
  });
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);

  QMenu* edit = menuBar()->addMenu(tr("&Edit"));
  QAction* undo = doc_->undoStack()->createUndoAction(this, tr("&Undo"));
  undo->setShortcut(QKeySequence::Undo);
  QAction* redo = doc_->undoStack()->createRedoAction(this, tr("&Redo"));
  redo->setShortcut(QKeySequence::Redo);
  edit->addAction(undo);
  edit->addAction(redo);
  edit->addSeparator();
  // On the scan selected in the scan list (also its context menu).
  auto with_scan = [this](const QString& what, std::function<void(const QString&)> act) {
    return [this, what, act] {
      if (SelectedScan().isEmpty()) {
        ShowError(what, tr("Select a scan in the scan list first."));
        return;
      }
      act(SelectedScan());
    };
  };
  QAction* rename = edit->addAction(tr("Re&name scan…"), this, with_scan(tr("Rename scan"), [this](const QString& s) {
    bool ok = false;
    const QString name = QInputDialog::getText(this, tr("Rename scan"), tr("New name of %1:").arg(s), QLineEdit::Normal, s, &ok);
    if (ok && name != s) RenameScan(s, name);
  }));
  QAction* remove = edit->addAction(tr("Re&move scan"), this,
                                    with_scan(tr("Remove scan"), [this](const QString& s) { RemoveScan(s); }));
  QAction* relink = edit->addAction(tr("Re&link scan file…"), this, with_scan(tr("Relink scan file"), [this, scan_filter](const QString& s) {
    const QString file = QFileDialog::getOpenFileName(this, tr("The file of %1").arg(s), LastDir(), scan_filter);
    if (!file.isEmpty()) RelinkScan(s, file);
  }));
  QAction* root = edit->addAction(tr("Set as r&oot of the scan order"), this,
                                  with_scan(tr("Set root"), [this](const QString& s) { SetRoot(s); }));
  scan_list_->setContextMenuPolicy(Qt::ActionsContextMenu);
  for (QAction* a : {rename, remove, relink, root}) scan_list_->addAction(a);

  QMenu* reg = menuBar()->addMenu(tr("&Registration"));
  QAction* run = reg->addAction(tr("&Register all scans"), this, [this] { RegisterProject(); });
  run->setShortcut(Qt::CTRL | Qt::Key_R);
  QAction* only_new = reg->addAction(tr("Register &unregistered scans"), this, [this] { RegisterUnregistered(); });
  QAction* refine_all =
      reg->addAction(tr("Refine all from &current poses"), this, [this] { RefineFromCurrentPoses(); });
  reg->addSeparator();
  QAction* pick = reg->addAction(tr("Align scan by &picked points…"), this,
                                 with_scan(tr("Align by picked points"), [this](const QString& s) { PickPoints(s); }));
  QAction* refine = reg->addAction(tr("Re&fine scan from its pose"), this,
                                   with_scan(tr("Refine scan"), [this](const QString& s) { RefineScan(s); }));
  QAction* edit_pose = reg->addAction(tr("Edit scan &pose…"), this, [this] { EditSelectedScanPose(); });
  QAction* release = reg->addAction(tr("Re&lease hand placement"), this,
                                    with_scan(tr("Release hand placement"),
                                              [this](const QString& s) { ReleaseHandPlacement(s); }));
  reg->addSeparator();
  QAction* pick_target = reg->addAction(tr("Pick a &target in scan…"), this,
                                        with_scan(tr("Pick a target"), [this](const QString& s) { PickTarget(s); }));
  pick_target->setObjectName("PickTargetAction");
  QAction* georef = reg->addAction(tr("&Georeference on control"), this, [this] { Georeference(); });
  georef->setObjectName("GeoreferenceAction");
  reg->addSeparator();
  QAction* settings = reg->addAction(tr("&Settings…"), this, [this] { EditRegisterSettings(); });
  for (QAction* a : {pick, refine, edit_pose, release, pick_target}) scan_list_->addAction(a);
  project_actions_ = {save,   save_as, run,  add,    report,    only_new, refine_all, pick,      refine,
                      rename, remove,  relink, root, edit_pose, release,  pick_target, georef, settings};

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), view3d_, &View3d::ResetCamera);
  QAction* refl = view->addAction(tr("Colour by &reflectance"));
  refl->setObjectName("ColourByReflectance");
  refl->setCheckable(true);
  refl->setChecked(scene_->colouring() == CloudColouring::kReflectance);
  connect(refl, &QAction::toggled, this, [this](bool on) {
    scene_->SetColouring(on ? CloudColouring::kReflectance : CloudColouring::kPerScan);
    QSettings().setValue("view/colour_by_reflectance", on);
  });
  QAction* full = view->addAction(tr("&Full resolution"));
  full->setObjectName("FullResolution");
  full->setCheckable(true);
  full->setToolTip(tr("Draw every point (a subset while the camera moves); otherwise at most %L1 points in all.")
                       .arg(ScanScene::kDecimatedPoints));
  connect(full, &QAction::toggled, scene_, &ScanScene::SetFullResolution);

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&About scanreg"), this, &MainWindow::ShowAbout);
}

void MainWindow::SetBusy(bool busy) {
  progress_->setVisible(busy);
  cancel_->setVisible(busy);
  if (busy) progress_->setValue(0);
  for (QAction* a : project_actions_) a->setEnabled(!busy && !project().scans.empty());
}

bool MainWindow::OpenProject(const QString& path, const QString& scan_folder) {
  Expected<io::Project> project = io::LoadProject(path.toStdString());
  if (!project) {
    ShowError(tr("Cannot open project"), QString::fromStdString(project.error().message));
    return false;
  }
  // Scan files that moved: looked for in scan_folder, or the user is asked for a folder.
  const bool relinked = !scan_folder.isEmpty() && pipeline::RelinkFromFolder(*project, scan_folder.toStdString()) > 0;
  const std::vector<std::string> missing = pipeline::MissingScanFiles(*project);
  if (!missing.empty()) {
    QStringList lines;
    for (const std::string& name : missing)
      lines << QString::fromStdString(name + ": " + project->scans[project->FindScan(name)].path.string());
    auto* box = new QMessageBox(QMessageBox::Warning, tr("Scan files missing"),
                                tr("%n scan file(s) of %1 are not where the project says:\n\n%2\n\nLocate the folder "
                                   "that holds them (the project is relinked to it; save to keep the new paths).",
                                   "", int(missing.size()))
                                    .arg(path, lines.join("\n")),
                                QMessageBox::Cancel, this);
    box->setObjectName("MissingFilesDialog");
    box->setAttribute(Qt::WA_DeleteOnClose);
    QPushButton* locate = box->addButton(tr("Locate folder…"), QMessageBox::AcceptRole);
    connect(locate, &QPushButton::clicked, this, [this, path] {
      const QString dir = QFileDialog::getExistingDirectory(this, tr("Folder with the missing scan files"), LastDir());
      if (!dir.isEmpty()) QTimer::singleShot(0, this, [this, path, dir] { OpenProject(path, dir); });
    });
    LogWarning(QString("%1: %2 scan file(s) missing").arg(path).arg(missing.size()).toStdString());
    box->open();
    return false;
  }
  return jobs_->Start<LoadedProject>(
      tr("Loading %1").arg(path),
      [p = std::move(*project), cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) {
        return LoadJob(p, cells, progress, cancel);
      },
      [this, relinked](LoadedProject& loaded) {
        OnProjectLoaded(std::move(loaded.project), std::move(loaded.previews));
        if (relinked) doc_->MarkChanged();  // the new paths are not saved yet
      });
}

void MainWindow::OnProjectLoaded(io::Project project, std::vector<pipeline::ScanPreview> previews) {
  doc_->Open(std::move(project), std::move(previews));
  if (!this->project().file.empty()) AddRecentProject(QString::fromStdString(this->project().file.string()));
}

bool MainWindow::OpenDemoProject(const QString& dir) {
  return jobs_->Start<LoadedProject>(
      tr("Simulating the demo project"),
      [dir, cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) -> Expected<LoadedProject> {
    SimulatedProjectOptions options;
    options.stations = 5;
    options.scanner.cols = 1500;
    options.scanner.rows = 375;
    SubProgress sim(progress, 0.0, 0.7);
    Expected<io::Project> project = pipeline::WriteSimulatedProject(options, dir.toStdString(), sim, cancel);
    if (!project) return project.error();
    SubProgress load(progress, 0.7, 1.0);
    return LoadJob(std::move(*project), cells, load, cancel);
      },
      [this](LoadedProject& loaded) { OnProjectLoaded(std::move(loaded.project), std::move(loaded.previews)); });
}

bool MainWindow::RegisterProject() { return StartRegistration(tr("register the scans"), RegistrationOptions(), true); }

bool MainWindow::StartRegistration(const QString& text, pipeline::RegisterOptions options, bool store_settings) {
  if (project().scans.empty()) return false;
  return jobs_->Start<Registered>(
      tr("Registering"),
      [project = project(), scans = doc_->FullScans(), options, store_settings](
          ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<Registered> {
    if (store_settings) pipeline::StoreRegisterSettings(options, &project.settings);  // as the CLI saves them
    Expected<pipeline::ProjectRegistration> r =
        pipeline::RegisterProjectScans(project, *scans, options, progress, cancel);
    if (!r) return r.error();
    return Registered{std::move(project), r->confusion};
      },
      [this, text](Registered& r) {
        doc_->ApplyRegistration(text, std::move(r.project), r.confusion);
        ReportRegistration();
      });
}

void MainWindow::SaveProjectAs() {
  QString path = QFileDialog::getSaveFileName(this, tr("Save project as"), LastDir(),
                                              tr("scanreg projects (*.scanreg.json)"));
  if (path.isEmpty()) return;
  // Open lists *.scanreg.json: a project saved under another name would be hidden from it.
  if (!path.endsWith(".scanreg.json")) path += path.endsWith(".json") ? QString() : QStringLiteral(".scanreg.json");
  RememberDir(path);
  SaveProject(path);
}

bool MainWindow::SaveProject(const QString& path) {
  // One writer per project (issue 16): a `scanreg-cli register` running on it holds its lock.
  Expected<io::ProjectLock> lock = io::ProjectLock::Acquire(path.toStdString(), "scanreg (saving from the GUI)");
  if (!lock) {
    ShowError(tr("Cannot save project"), QString::fromStdString(lock.error().message));
    return false;
  }
  std::uint64_t digest = 0;
  if (Status s = io::SaveProject(project(), path.toStdString(), &digest); !s) {
    if (s.error().code == ErrorCode::kConflict) {
      OfferReload(path, QString::fromStdString(s.error().message));
    } else {
      ShowError(tr("Cannot save project"), QString::fromStdString(s.error().message));
    }
    return false;
  }
  doc_->MarkSaved(std::filesystem::absolute(path.toStdString()), digest);
  statusBar()->showMessage(tr("Saved %1").arg(path), 5000);
  return true;
}

pipeline::RegisterOptions MainWindow::RegistrationOptions() const {
  Expected<pipeline::RegisterOptions> saved = pipeline::ProjectRegisterOptions(project());
  pipeline::RegisterOptions options = saved ? *saved : pipeline::RegisterOptions();
  if (!saved) LogWarning(saved.error().message + "; the defaults are used (Registration → Settings… sets them)");
  options.feature_cache_dir = pipeline::ProjectCacheDir(project());
  return options;
}

bool MainWindow::SetRegisterOptions(const pipeline::RegisterOptions& options) {
  io::Project after = project();
  pipeline::StoreRegisterSettings(options, &after.settings);
  if (after.settings == project().settings) return false;
  doc_->Edit(tr("change the registration settings"), std::move(after));
  return true;
}

RegisterSettingsDialog* MainWindow::EditRegisterSettings() {
  auto* dialog = new RegisterSettingsDialog(RegistrationOptions(), this);
  dialog->setAttribute(Qt::WA_DeleteOnClose);
  connect(dialog, &QDialog::accepted, this, [this, dialog] {
    if (auto options = dialog->Options()) SetRegisterOptions(*options);
  });
  dialog->open();
  return dialog;
}

void MainWindow::ReportRegistration() {
  int registered = 0, on_hand = 0;
  QStringList left_out;
  const std::vector<bool> rests = io::RestsOnHandPlacement(project());
  for (std::size_t i = 0; i < project().scans.size(); ++i) {
    const io::ProjectScan& s = project().scans[i];
    registered += s.registered;
    on_hand += s.registered && rests[i];
    if (!s.registered)
      left_out << QString::fromStdString(s.name) + " (" + QString::fromStdString(s.unregistered_reason) + ")";
  }
  QString summary = tr("Registered %1 of %2 scans").arg(registered).arg(project().scans.size());
  if (on_hand > 0) summary += tr("; %n rest(s) on a hand placement", "", on_hand);
  if (!left_out.isEmpty()) summary += tr("; not registered: %1").arg(left_out.join("; "));
  LogInfo(summary.toStdString());
  last_summary_ = summary;
}

void MainWindow::OnJobFailed(const QString& title, const QString& message, bool cancelled) {
  SetBusy(false);
  if (cancelled) {
    statusBar()->showMessage(title + tr(": cancelled; the project is unchanged"), 8000);
    return;
  }
  ShowError(title, message);
}

void MainWindow::Refresh() {
  const io::Project& p = project();
  const Eigen::MatrixXi& c = confusion();
  scan_list_->Show(p, previews());
  // The confusion matrix in scan order (root, then as the registration placed the scans), as in the
  // report; empty when there is none, so no stale matrix is shown.
  const std::vector<int> order = io::OrderedScanIndices(p);
  std::vector<std::string> names;
  for (int i : order) names.push_back(p.scans[i].name);
  Eigen::MatrixXi ordered;
  if (c.rows() == static_cast<Eigen::Index>(order.size()) && c.cols() == c.rows()) {
    ordered.resize(c.rows(), c.cols());
    for (std::size_t i = 0; i < order.size(); ++i)
      for (std::size_t j = 0; j < order.size(); ++j) ordered(i, j) = c(order[i], order[j]);
  }
  confusion_panel_->Show(ordered, names);
  network_->Show(p);
  control_panel_->Show(p);
  bool any_registered = false;
  for (const io::ProjectScan& s : p.scans) any_registered |= s.registered;
  // Before registration, show the scans as they stand (each at its current pose).
  io::Project shown = p;
  if (!any_registered)
    for (io::ProjectScan& s : shown.scans) s.registered = true;
  scene_->ShowScans(shown, previews());
  UpdateTitle();
}

void MainWindow::UpdateTitle() {
  const QString name = project().file.empty() ? tr("unsaved project")
                                              : QString::fromStdString(project().file.filename().string());
  setWindowTitle(tr("scanreg — %1[*]").arg(name));  // [*]: the modified marker
  setWindowModified(doc_->dirty());
}

void MainWindow::OfferReload(const QString& path, const QString& message) {
  LogWarning(message.toStdString());
  auto* box = new QMessageBox(QMessageBox::Warning, tr("The project changed on disk"),
                              message + tr("\n\nReload it (your unsaved changes are lost), save your version under "
                                           "another name, or cancel and decide later."),
                              QMessageBox::NoButton, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ConflictDialog");
  QPushButton* reload = box->addButton(tr("Reload from disk"), QMessageBox::DestructiveRole);
  reload->setObjectName("ReloadButton");
  QPushButton* save_as = box->addButton(tr("Save as…"), QMessageBox::AcceptRole);
  save_as->setObjectName("SaveAsButton");
  box->addButton(QMessageBox::Cancel);
  connect(box, &QMessageBox::buttonClicked, this, [this, box, reload, save_as, path](QAbstractButton* clicked) {
    if (clicked == reload) {
      OpenProject(path);  // the user chose to drop the unsaved changes
    } else if (clicked == save_as) {
      QTimer::singleShot(0, this, &MainWindow::SaveProjectAs);
    }
  });
  box->open();
}

void MainWindow::ShowError(const QString& title, const QString& message) {
  LogError(title.toStdString() + ": " + message.toStdString());
  auto* box = new QMessageBox(QMessageBox::Warning, title, message, QMessageBox::Ok, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ErrorDialog");
  box->open();  // window-modal, does not block the event loop
}

bool MainWindow::MaybeSaveChanges() {
  if (!dirty()) return true;
  QMessageBox box(QMessageBox::Question, tr("Unsaved changes"),
                  tr("The changes to %1 have not been saved. Save them first?")
                      .arg(QString::fromStdString(project().file.filename().string())),
                  QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel, this);
  box.setObjectName("UnsavedChangesDialog");
  const int answer = box.exec();
  if (answer == QMessageBox::Cancel) return false;
  if (answer == QMessageBox::Discard) return true;
  if (project().file.empty()) {
    SaveProjectAs();
    return !dirty();
  }
  return SaveProject(QString::fromStdString(project().file.string()));
}

void MainWindow::FillRecentMenu(QMenu* menu) {
  const QStringList missing = RemoveMissingRecentProjects();
  if (!missing.isEmpty()) {
    statusBar()->showMessage(
        tr("Removed from the recent projects (the files no longer exist): %1").arg(missing.join(", ")), 10000);
    LogWarning("removed from the recent projects, the files no longer exist: " + missing.join(", ").toStdString());
  }
  menu->clear();
  for (const QString& path : RecentProjects()) {
    menu->addAction(QFileInfo(path).fileName() + "  —  " + QFileInfo(path).absolutePath(), this, [this, path] {
      if (MaybeSaveChanges()) OpenProject(path);
    });
  }
  if (menu->isEmpty()) menu->addAction(tr("(no recent projects)"))->setEnabled(false);
}

bool MainWindow::NewProject(const QStringList& scan_files, const QString& project_path) {
  std::vector<std::filesystem::path> files;
  for (const QString& f : scan_files) files.push_back(f.toStdString());
  return jobs_->Start<AddedScans>(
      tr("Creating %1").arg(project_path),
      [files, path = project_path.toStdString(), cells = doc_->previewCells()](ProgressSink& progress,
                                                  const CancelToken& cancel) -> Expected<AddedScans> {
        pipeline::CreateProjectOptions options;
        options.scan_files = files;
        options.skip_unreadable = true;  // one bad file does not stop the others
        SubProgress create(progress, 0.0, 0.8);
        Expected<pipeline::CreatedProject> created = pipeline::CreateProject(path, options, create, cancel);
        if (!created) return created.error();
        SubProgress previews(progress, 0.8, 1.0);  // read back from the scan cache the creation filled
        Expected<LoadedProject> loaded = LoadJob(std::move(created->project), cells, previews, cancel);
        if (!loaded) return loaded.error();
        return AddedScans{std::move(loaded->project), std::move(loaded->previews), std::move(created->skipped)};
      },
      [this](AddedScans& created) {
        OnProjectLoaded(std::move(created.project), std::move(created.previews));
        ShowSkippedFiles(created.skipped);
      });
}

bool MainWindow::AddScans(const QStringList& scan_files) {
  if (project().file.empty()) {
    ShowError(tr("No project open"), tr("Create a project first (File → New project…), then add scans to it."));
    return false;
  }
  std::vector<std::filesystem::path> files;
  for (const QString& f : scan_files) files.push_back(f.toStdString());
  return jobs_->Start<AddedScans>(
      tr("Adding scans"),
      [files, project = project(), cells = doc_->previewCells()](ProgressSink& progress, const CancelToken& cancel) mutable -> Expected<AddedScans> {
        std::vector<std::string> skipped;
        const std::size_t before = project.scans.size();
        SubProgress append(progress, 0.0, 0.8);
        if (Status s = pipeline::AppendScanFiles(project, files, append, cancel, &skipped); !s) return s.error();
        std::vector<int> added;
        for (std::size_t i = before; i < project.scans.size(); ++i) added.push_back(static_cast<int>(i));
        std::vector<pipeline::ScanPreview> previews;
        if (!added.empty()) {
          SubProgress load(progress, 0.8, 1.0);  // read back from the scan cache the append filled
          Expected<std::vector<pipeline::ScanPreview>> p = pipeline::LoadScanPreviews(
              project, pipeline::PreviewCellsPerScan(project.scans.size(), cells), load, cancel, added);
          if (!p) return p.error();
          previews = std::move(*p);
        }
        return AddedScans{std::move(project), std::move(previews), std::move(skipped)};
      },
      [this](AddedScans& added) {
        if (!added.previews.empty()) doc_->AppendScans(std::move(added.project), std::move(added.previews));
        ShowSkippedFiles(added.skipped);
      });
}

void MainWindow::ShowSkippedFiles(const std::vector<std::string>& skipped) {
  if (skipped.empty()) return;
  QString list;
  for (const std::string& why : skipped) list += "• " + QString::fromStdString(why) + "\n";
  ShowError(tr("%n file(s) not added", "", int(skipped.size())),
            tr("The other files were added. These were left out:\n\n%1").arg(list));
}

bool MainWindow::ExportReport(const QString& dir) {
  if (project().scans.empty()) return false;
  return jobs_->Start<std::filesystem::path>(
      tr("Writing the report to %1").arg(dir),
      [project = project(), dir = dir.toStdString()](ProgressSink& progress, const CancelToken& cancel) {
        return report::WriteReport(project, dir, progress, cancel);
      },
      [](std::filesystem::path& index) { LogInfo("report written: " + index.string()); });
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (jobs_->busy()) {
    QMessageBox box(QMessageBox::Question, tr("A job is running"),
                    tr("%1 is still running. Cancel it and close?").arg(statusBar()->currentMessage()),
                    QMessageBox::Yes | QMessageBox::No, this);
    box.setObjectName("CloseDuringJobDialog");
    if (box.exec() != QMessageBox::Yes) {
      event->ignore();
      return;
    }
    jobs_->Cancel();  // the runner joins the worker when the window goes
  }
  if (!MaybeSaveChanges()) {
    event->ignore();
    return;
  }
  QSettings settings;
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  event->accept();
}

void MainWindow::ShowAbout() {
  QMessageBox::about(
      this, tr("About scanreg"),
      tr("<b>scanreg</b> %1<br>Registration of terrestrial laser scans.").arg(QApplication::applicationVersion()));
}

QWidget* MainWindow::Scrollable(QWidget* content) {
  auto* area = new QScrollArea;
  area->setObjectName(content->objectName() + "Scroll");
  area->setWidget(content);
  area->setWidgetResizable(true);
  area->setFrameShape(QFrame::NoFrame);
  return area;
}

bool MainWindow::SaveScreenshot(const QString& path) {
  const QImage image = Screenshot();
  return !image.isNull() && image.save(path);
}

QImage MainWindow::Screenshot() {
  QImage image = grab().toImage();
  // QWidget::grab() does not capture the OpenGL frame buffer; paint the VTK frame on top.
  const QImage frame = view3d_->GrabImage();
  if (!frame.isNull()) {
    QPainter painter(&image);
    const QPoint origin = view3d_->vtkWidget()->mapTo(this, QPoint(0, 0));
    painter.drawImage(QRect(origin, view3d_->vtkWidget()->size()), frame);
  }
  return image;
}

}  // namespace scanreg::ui
