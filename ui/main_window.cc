// The main window: its docks, the status bar's progress and Cancel, the registration jobs, the
// panels' refresh and its screenshots. Its menus are in main_window_menus.cc, the project files in
// main_window_files.cc, the user's edits in main_window_edits.cc, georeferencing in main_window_georef.cc.
#include "ui/main_window.h"

#include <QVTKOpenGLNativeWidget.h>
#include <QAction>
#include <QApplication>
#include <QCloseEvent>
#include <QDockWidget>
#include <QMessageBox>
#include <QPainter>
#include <QProgressBar>
#include <QPushButton>
#include <QScrollArea>
#include <QScreen>
#include <QSettings>
#include <QShortcut>
#include <QStatusBar>

#include "core/common/log.h"
#include "core/io/project_tree.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/register_settings.h"
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

struct Registered {
  io::Project project;
  Eigen::MatrixXi confusion;
};

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

void MainWindow::SetBusy(bool busy) {
  progress_->setVisible(busy);
  cancel_->setVisible(busy);
  if (busy) progress_->setValue(0);
  for (QAction* a : project_actions_) a->setEnabled(!busy && !project().scans.empty());
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
  QStringList left_out, not_verified;
  const std::vector<bool> rests = io::RestsOnHandPlacement(project());
  for (std::size_t i = 0; i < project().scans.size(); ++i) {
    const io::ProjectScan& s = project().scans[i];
    registered += s.registered;
    on_hand += s.registered && rests[i];
    if (!s.registered)
      (s.unverified ? not_verified : left_out)
          << QString::fromStdString(s.name) + " (" + QString::fromStdString(s.unregistered_reason) + ")";
  }
  QString summary = tr("Registered %1 of %2 scans").arg(registered).arg(project().scans.size());
  if (on_hand > 0) summary += tr("; %n rest(s) on a hand placement", "", on_hand);
  if (!not_verified.isEmpty())
    summary += tr("; placed but not verified (accept the link if the pose is right): %1").arg(not_verified.join("; "));
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

void MainWindow::ShowError(const QString& title, const QString& message) {
  LogError(title.toStdString() + ": " + message.toStdString());
  auto* box = new QMessageBox(QMessageBox::Warning, title, message, QMessageBox::Ok, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ErrorDialog");
  box->open();  // window-modal, does not block the event loop
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
