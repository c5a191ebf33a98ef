// The main window's menus: File, Edit (also the scan list's context menu), Registration, View
// and Help. The actions call the window's public operations; those on the project are enabled only
// with a project and no running job.
#include <QAction>
#include <QActionGroup>
#include <QApplication>
#include <QFileDialog>
#include <QFileInfo>
#include <QInputDialog>
#include <QLineEdit>
#include <QMenuBar>
#include <QMessageBox>
#include <QSettings>
#include <QStandardPaths>
#include <QStatusBar>
#include <QUndoStack>

#include "core/common/log.h"
#include "core/io/scan_file.h"
#include "ui/app_settings.h"
#include "ui/main_window.h"
#include "ui/project_document.h"
#include "ui/project_panels.h"
#include "ui/scan_cloud_actors.h"
#include "ui/scan_scene.h"
#include "ui/view_3d.h"

namespace scanreg::ui {

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

  CreateViewMenu();

  QMenu* help = menuBar()->addMenu(tr("&Help"));
  help->addAction(tr("&About scanreg"), this, &MainWindow::ShowAbout);
}

void MainWindow::CreateViewMenu() {
  QMenu* view = menuBar()->addMenu(tr("&View"));
  view->addAction(tr("&Reset camera"), view3d_, &View3d::ResetCamera);
  // How the points are coloured: one exclusive choice, kept in the settings.
  QMenu* colour = view->addMenu(tr("&Colour points by"));
  auto* colourings = new QActionGroup(this);
  const struct {
    CloudColouring colouring;
    QString text, name, setting, tip;
  } choices[] = {
      {CloudColouring::kPerScan, tr("&Scan"), "ColourPerScan", "scan", tr("One colour per scan, as its marker")},
      {CloudColouring::kReflectance, tr("&Reflectance"), "ColourByReflectance", "reflectance",
       tr("Grey by each point's reflectance (intensity)")},
      {CloudColouring::kScannerColour, tr("Scanner &colour (RGB)"), "ColourByScannerColour", "colour",
       tr("Each point's colour from the scanner's camera; a scan without colour is drawn grey by reflectance")},
  };
  QSettings settings;
  // "view/colour_by_reflectance": the setting of versions before the scanner's colour was drawn.
  const QString saved = settings.value("view/colouring", settings.value("view/colour_by_reflectance").toBool()
                                                             ? QStringLiteral("reflectance")
                                                             : QStringLiteral("scan"))
                            .toString();
  for (const auto& choice : choices) {
    QAction* a = colour->addAction(choice.text);
    a->setObjectName(choice.name);
    a->setToolTip(choice.tip);
    a->setStatusTip(choice.tip);
    a->setCheckable(true);
    colourings->addAction(a);
    if (choice.setting == saved) {
      a->setChecked(true);
      scene_->SetColouring(choice.colouring);
    }
    connect(a, &QAction::toggled, this, [this, c = choice.colouring, setting = choice.setting](bool on) {
      if (!on) return;
      scene_->SetColouring(c);
      QSettings().setValue("view/colouring", setting);
      if (c != CloudColouring::kScannerColour || previews().empty()) return;
      int coloured = 0;
      for (const pipeline::ScanPreview& p : previews()) coloured += p.scan.HasColour();
      if (coloured < static_cast<int>(previews().size()))
        statusBar()->showMessage(tr("%1 of %n scan(s) have the scanner's colour; the others are drawn grey by "
                                    "reflectance", "", int(previews().size())).arg(coloured), 10000);
    });
  }
  if (!colourings->checkedAction()) colourings->actions().front()->setChecked(true);
  QAction* full = view->addAction(tr("&Full resolution"));
  full->setObjectName("FullResolution");
  full->setCheckable(true);
  full->setToolTip(tr("Draw every point (a subset while the camera moves); otherwise at most %L1 points in all.")
                       .arg(ScanScene::kDecimatedPoints));
  connect(full, &QAction::toggled, scene_, &ScanScene::SetFullResolution);
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

void MainWindow::ShowAbout() {
  QMessageBox::about(
      this, tr("About scanreg"),
      tr("<b>scanreg</b> %1<br>Registration of terrestrial laser scans.").arg(QApplication::applicationVersion()));
}

}  // namespace scanreg::ui
