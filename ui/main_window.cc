#include "ui/main_window.h"

#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDockWidget>
#include <QFileDialog>
#include <QMenuBar>
#include <QMessageBox>
#include <QPainter>
#include <QProgressBar>
#include <QPushButton>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QUndoStack>
#include <QVTKOpenGLNativeWidget.h>

#include "core/common/log.h"
#include "core/pipeline/apply_pair_result.h"
#include "core/pipeline/create_project.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "ui/job_runner.h"
#include "ui/network_panel.h"
#include "ui/pair_inspector.h"
#include "ui/project_panels.h"
#include "ui/scan_cloud_actors.h"
#include "ui/view_3d.h"

namespace scanreg::ui {
namespace {

// An edit of the project (override, accept / reject), undone by restoring the snapshot before it.
class EditCommand : public QUndoCommand {
 public:
  EditCommand(MainWindow* window, const QString& text, io::Project before, io::Project after, bool rerun)
      : QUndoCommand(text), window_(window), before_(std::move(before)), after_(std::move(after)), rerun_(rerun) {}
  void undo() override { window_->ApplyEdit(before_, false); }
  void redo() override { window_->ApplyEdit(after_, rerun_); }

 private:
  MainWindow* window_;
  io::Project before_, after_;
  bool rerun_;
};

struct LoadedProject {
  io::Project project;
  std::vector<Scan> scans;
};

struct Registered {
  io::Project project;
  Eigen::MatrixXi confusion;
};

Expected<std::any> LoadJob(io::Project project, ProgressSink& progress, const CancelToken& cancel) {
  Expected<std::vector<Scan>> scans = pipeline::LoadProjectScans(project, progress, cancel);
  if (!scans) return scans.error();
  return std::any(LoadedProject{std::move(project), std::move(*scans)});
}

}  // namespace

MainWindow::MainWindow(QWidget* parent) : QMainWindow(parent) {
  setWindowTitle(tr("scanreg — terrestrial laser scan registration"));
  setObjectName("MainWindow");
  jobs_ = new JobRunner(this);
  undo_ = new QUndoStack(this);
  view3d_ = new View3d(this);
  view3d_->setObjectName("View3d");
  setCentralWidget(view3d_);
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
  connect(jobs_, &JobRunner::Started, this, [this](const QString& title) {
    SetBusy(true);
    statusBar()->showMessage(title + "…");
  });
  connect(jobs_, &JobRunner::Progress, this, [this](double f, const QString& stage) {
    progress_->setValue(static_cast<int>(f * 1000));
    statusBar()->showMessage(stage);
  });
  connect(jobs_, &JobRunner::Succeeded, this, &MainWindow::OnJobSucceeded);
  connect(jobs_, &JobRunner::Failed, this, &MainWindow::OnJobFailed);
  inspector_ = new PairInspector(this);  // after the window's own job connections

  // Core log messages arrive on any thread: forward them queued to the log panel.
  // The handler is removed in the destructor (under the log's mutex) before the panel dies, and a
  // queued call to a deleted context object is dropped by Qt.
  LogPanel* log = log_;
  SetLogHandler([log](LogLevel level, const std::string& message) {
    const QString lvl = level == LogLevel::kError ? "error" : level == LogLevel::kWarning ? "warning" : "info";
    const QString text = QString::fromStdString(message);
    QMetaObject::invokeMethod(log, [log, lvl, text] { log->Append(lvl, text); }, Qt::QueuedConnection);
  });

  statusBar()->showMessage(tr("No project open."));
  resize(1400, 900);
  QSettings settings;
  restoreGeometry(settings.value("window/geometry").toByteArray());
  restoreState(settings.value("window/state").toByteArray());
  SetBusy(false);
}

MainWindow::~MainWindow() { SetLogHandler({}); }

void MainWindow::CreateDocks() {
  scan_list_ = new ScanListPanel(this);
  confusion_panel_ = new ConfusionPanel(this);
  network_ = new NetworkPanel(this);
  log_ = new LogPanel(this);
  connect(network_, &NetworkPanel::ParentOverrideRequested, this, &MainWindow::SetParentOverride);
  connect(network_, &NetworkPanel::LinkDecisionRequested, this, &MainWindow::SetLinkDecision);
  const std::pair<QWidget*, QString> docks[] = {{scan_list_, tr("Scans")},
                                                {network_, tr("Scan network")},
                                                {confusion_panel_, tr("Confusion matrix")},
                                                {log_, tr("Log")}};
  for (const auto& [widget, title] : docks) {
    auto* dock = new QDockWidget(title, this);
    dock->setObjectName(widget->objectName() + "Dock");
    dock->setWidget(widget);
    addDockWidget(widget == log_ ? Qt::BottomDockWidgetArea : Qt::RightDockWidgetArea, dock);
  }
}

void MainWindow::CreateMenus() {
  QMenu* file = menuBar()->addMenu(tr("&File"));
  file->setObjectName("FileMenu");
  QAction* open = file->addAction(tr("&Open project…"), this, [this] {
    const QString path = QFileDialog::getOpenFileName(this, tr("Open project"), QString(),
                                                      tr("scanreg projects (*.scanreg.json);;All files (*)"));
    if (!path.isEmpty()) OpenProject(path);
  });
  open->setShortcut(QKeySequence::Open);
  file->addAction(tr("Open &demo project"), this, [this] {
    const QString dir = QStandardPaths::writableLocation(QStandardPaths::TempLocation) + "/scanreg-demo";
    OpenDemoProject(dir);
  });
  QAction* save = file->addAction(tr("&Save project"), this, [this] { SaveProject(QString::fromStdString(project_.file.string())); });
  save->setShortcut(QKeySequence::Save);
  QAction* save_as = file->addAction(tr("Save project &as…"), this, [this] {
    const QString path = QFileDialog::getSaveFileName(this, tr("Save project as"), QString(),
                                                      tr("scanreg projects (*.scanreg.json)"));
    if (!path.isEmpty()) SaveProject(path);
  });
  file->addSeparator();
  QAction* quit = file->addAction(tr("&Quit"), this, &QWidget::close);
  quit->setShortcut(QKeySequence::Quit);

  QMenu* edit = menuBar()->addMenu(tr("&Edit"));
  QAction* undo = undo_->createUndoAction(this, tr("&Undo"));
  undo->setShortcut(QKeySequence::Undo);
  QAction* redo = undo_->createRedoAction(this, tr("&Redo"));
  redo->setShortcut(QKeySequence::Redo);
  edit->addAction(undo);
  edit->addAction(redo);

  QMenu* reg = menuBar()->addMenu(tr("&Registration"));
  QAction* run = reg->addAction(tr("&Register all scans"), this, [this] { RegisterProject(); });
  run->setShortcut(Qt::CTRL | Qt::Key_R);
  project_actions_ = {save, save_as, run};

  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), view3d_, &View3d::ResetCamera);
  QAction* refl = view->addAction(tr("Colour by &reflectance"));
  refl->setCheckable(true);
  connect(refl, &QAction::toggled, this, [this](bool on) {
    colour_by_reflectance_ = on;
    Refresh();
  });

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&About scanreg"), this, &MainWindow::ShowAbout);
}

void MainWindow::SetBusy(bool busy) {
  progress_->setVisible(busy);
  cancel_->setVisible(busy);
  if (busy) progress_->setValue(0);
  for (QAction* a : project_actions_) a->setEnabled(!busy && !project_.scans.empty());
}

bool MainWindow::OpenProject(const QString& path) {
  Expected<io::Project> project = io::LoadProject(path.toStdString());
  if (!project) {
    ShowError(tr("Cannot open project"), QString::fromStdString(project.error().message));
    return false;
  }
  return jobs_->Start(tr("Loading %1").arg(path), [p = std::move(*project)](ProgressSink& progress,
                                                                             const CancelToken& cancel) {
    return LoadJob(p, progress, cancel);
  });
}

bool MainWindow::OpenDemoProject(const QString& dir) {
  return jobs_->Start(tr("Simulating the demo project"), [dir](ProgressSink& progress, const CancelToken& cancel) {
    SimulatedProjectOptions options;
    options.stations = 5;
    options.scanner.cols = 1500;
    options.scanner.rows = 375;
    SubProgress sim(progress, 0.0, 0.7);
    Expected<io::Project> project = pipeline::WriteSimulatedProject(options, dir.toStdString(), sim, cancel);
    if (!project) return Expected<std::any>(project.error());
    SubProgress load(progress, 0.7, 1.0);
    return LoadJob(std::move(*project), load, cancel);
  });
}

bool MainWindow::RegisterProject() {
  if (project_.scans.empty()) return false;
  const pipeline::RegisterOptions options = RegistrationOptions();
  return jobs_->Start(tr("Registering"), [project = project_, scans = scans_, options](
                                             ProgressSink& progress, const CancelToken& cancel) mutable {
    Expected<pipeline::ProjectRegistration> r =
        pipeline::RegisterProjectScans(project, scans, options, progress, cancel);
    if (!r) return Expected<std::any>(r.error());
    return Expected<std::any>(std::any(Registered{std::move(project), r->confusion}));
  });
}

bool MainWindow::SaveProject(const QString& path) {
  if (Status s = io::SaveProject(project_, path.toStdString()); !s) {
    ShowError(tr("Cannot save project"), QString::fromStdString(s.error().message));
    return false;
  }
  project_.file = std::filesystem::absolute(path.toStdString());
  dirty_ = false;
  statusBar()->showMessage(tr("Saved %1").arg(path), 5000);
  return true;
}

void MainWindow::SetParentOverride(const QString& child, const QString& parent) {
  const int c = project_.FindScan(child.toStdString());
  if (c < 0 || child == parent || (!parent.isEmpty() && project_.FindScan(parent.toStdString()) < 0)) return;
  io::Project after = project_;
  if (parent.isEmpty()) {
    after.scans[c].parent_override.reset();
  } else {
    after.scans[c].parent_override = parent.toStdString();
  }
  const QString text = parent.isEmpty() ? tr("clear the parent of %1").arg(child)
                                        : tr("register %1 to %2").arg(child, parent);
  undo_->push(new EditCommand(this, text, project_, std::move(after), true));
}

void MainWindow::SetLinkDecision(const QString& parent, const QString& child, bool accept, bool reject) {
  io::Project after = project_;
  bool found = false;
  for (io::LinkRecord& l : after.links) {
    if (l.parent != parent.toStdString() || l.child != child.toStdString()) continue;
    l.user_accepted = accept;
    l.user_rejected = reject;
    found = true;
  }
  if (!found) return;
  const QString text = reject ? tr("reject %1 → %2").arg(child, parent)
                              : accept ? tr("accept %1 → %2").arg(child, parent)
                                       : tr("clear the decision on %1 → %2").arg(child, parent);
  undo_->push(new EditCommand(this, text, project_, std::move(after), reject));
}

pipeline::RegisterOptions MainWindow::RegistrationOptions() const {
  pipeline::RegisterOptions options;
  options.feature_cache_dir = project_.file.parent_path() / ".scanreg-cache";
  return options;
}

bool MainWindow::UsePairResult(const io::LinkRecord& link) {
  io::Project after = project_;
  if (Status s = pipeline::ApplyPairResult(link, after); !s) {
    ShowError(tr("Cannot use this pair registration"), QString::fromStdString(s.error().message));
    return false;
  }
  const QString text = tr("use the pair registration %1 → %2 (%3)")
                           .arg(QString::fromStdString(link.child), QString::fromStdString(link.parent),
                                QString::fromStdString(link.method));
  undo_->push(new EditCommand(this, text, project_, std::move(after), false));
  return true;
}

void MainWindow::ApplyEdit(const io::Project& project, bool rerun) {
  project_ = project;
  for (std::size_t i = 0; i < scans_.size() && i < project_.scans.size(); ++i)
    scans_[i].world_from_scan = project_.scans[i].world_from_scan;
  dirty_ = true;
  Refresh();
  if (rerun && !jobs_->busy()) RegisterProject();
}

void MainWindow::OnJobSucceeded(const QString& title, std::any result) {
  SetBusy(false);
  if (auto* loaded = std::any_cast<LoadedProject>(&result)) {
    project_ = std::move(loaded->project);
    scans_ = std::move(loaded->scans);
    undo_->clear();
    confusion_.resize(0, 0);
    dirty_ = false;
    QSettings().setValue("recent/project", QString::fromStdString(project_.file.string()));
  } else if (auto* reg = std::any_cast<Registered>(&result)) {
    project_ = std::move(reg->project);
    confusion_ = reg->confusion;
    for (std::size_t i = 0; i < scans_.size() && i < project_.scans.size(); ++i)
      scans_[i].world_from_scan = project_.scans[i].world_from_scan;
    dirty_ = true;
  }
  SetBusy(false);
  Refresh();
  statusBar()->showMessage(title + tr(": done"), 5000);
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
  scan_list_->Show(project_, scans_);
  std::vector<std::string> names;
  for (const io::ProjectScan& s : project_.scans) names.push_back(s.name);
  if (confusion_.size() > 0) confusion_panel_->Show(confusion_, names);
  network_->Show(project_);
  bool any_registered = false;
  for (const io::ProjectScan& s : project_.scans) any_registered |= s.registered;
  // Before registration, show the scans as they stand (each at its current pose).
  io::Project shown = project_;
  if (!any_registered)
    for (io::ProjectScan& s : shown.scans) s.registered = true;
  view3d_->SetActors(MakeScanActors(scans_, shown,
                                    colour_by_reflectance_ ? CloudColouring::kReflectance : CloudColouring::kPerScan,
                                    150000));
  setWindowTitle(tr("scanreg — %1").arg(QString::fromStdString(project_.file.filename().string())));
  emit ProjectChanged();
}

void MainWindow::ShowError(const QString& title, const QString& message) {
  LogError(title.toStdString() + ": " + message.toStdString());
  auto* box = new QMessageBox(QMessageBox::Warning, title, message, QMessageBox::Ok, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ErrorDialog");
  box->open();  // window-modal, does not block the event loop
}

void MainWindow::closeEvent(QCloseEvent* event) {
  if (dirty_) {
    const auto answer = QMessageBox::question(this, tr("Unsaved changes"),
                                              tr("The registration has not been saved. Save it before closing?"),
                                              QMessageBox::Save | QMessageBox::Discard | QMessageBox::Cancel);
    if (answer == QMessageBox::Cancel || (answer == QMessageBox::Save &&
                                          !SaveProject(QString::fromStdString(project_.file.string())))) {
      event->ignore();
      return;
    }
  }
  QSettings settings;
  settings.setValue("window/geometry", saveGeometry());
  settings.setValue("window/state", saveState());
  event->accept();
}

void MainWindow::ShowAbout() {
  QMessageBox::about(this, tr("About scanreg"),
                     tr("<b>scanreg</b> %1<br>Registration of terrestrial laser scans.")
                         .arg(QApplication::applicationVersion()));
}

bool MainWindow::SaveScreenshot(const QString& path) {
  QImage image = grab().toImage();
  // QWidget::grab() does not capture the OpenGL frame buffer; paint the VTK frame on top.
  const QImage frame = view3d_->GrabImage();
  if (!frame.isNull()) {
    QPainter painter(&image);
    const QPoint origin = view3d_->vtkWidget()->mapTo(this, QPoint(0, 0));
    painter.drawImage(QRect(origin, view3d_->vtkWidget()->size()), frame);
  }
  return !image.isNull() && image.save(path);
}

}  // namespace scanreg::ui
