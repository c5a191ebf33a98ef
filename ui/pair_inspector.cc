#include "ui/pair_inspector.h"

#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <QDockWidget>
#include <QEvent>
#include <QGraphicsItem>
#include <QHeaderView>
#include <QMouseEvent>
#include <QTimer>

#include "core/features/feature_cache.h"
#include "core/features/panorama.h"
#include "core/io/project_tree.h"
#include "ui/distance_overlay.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/project_document.h"
#include "ui/network_panel.h"
#include "ui/pair_panel.h"
#include "ui/project_panels.h"
#include "ui/view_3d.h"

namespace scanreg::ui {
namespace {

constexpr double kOverlayScaleMax_m = 0.05;  // distance drawn red in the 3D preview

struct PairJobResult {
  PanoramaImage parent, child;
  pipeline::PairInspection inspection;
};

Expected<ScanFeatures> Features(const Scan& scan, const pipeline::RegisterOptions& options) {
  return options.feature_cache_dir.empty() ? DetectFeatures(scan, options.sift)
                                           : LoadOrDetectFeatures(scan, options.sift, options.feature_cache_dir);
}

// The link's methods ("3d+dense") when the project holds the pair.
std::optional<std::pair<CoarseMethod, pipeline::FineMethod>> LinkMethods(const io::Project& project,
                                                                         const std::string& parent,
                                                                         const std::string& child) {
  for (const io::LinkRecord& l : project.links) {
    if (l.parent != parent || l.child != child) continue;
    for (CoarseMethod c : pipeline::AllCoarseMethods())
      for (pipeline::FineMethod f : pipeline::AllFineMethods())
        if (l.method == std::string(pipeline::CoarseMethodName(c)) + "+" + pipeline::FineMethodName(f))
          return std::make_pair(c, f);
  }
  return std::nullopt;
}

// Double-clicks on the scan network: a scan shows its panorama, a link (the nearest within a few
// pixels) opens its pair; elsewhere the view fits the network.
class NetworkClicks : public QObject {
 public:
  NetworkClicks(NetworkPanel* network, PairInspector* inspector)
      : QObject(inspector), network_(network), inspector_(inspector) {}

 protected:
  bool eventFilter(QObject*, QEvent* event) override {
    if (event->type() != QEvent::MouseButtonDblClick) return false;
    const QPoint at = static_cast<QMouseEvent*>(event)->pos();
    const QString scan = network_->ScanAt(at);
    if (!scan.isEmpty()) return inspector_->ShowScan(scan);
    const std::vector<int> links = network_->LinksNear(at);
    if (links.empty()) return false;
    const io::LinkRecord& l = network_->project().links[links.front()];
    return inspector_->OpenPair(QString::fromStdString(l.parent), QString::fromStdString(l.child));
  }

 private:
  NetworkPanel* network_;
  PairInspector* inspector_;
};

}  // namespace

PairInspector::PairInspector(MainWindow* window) : QObject(window), window_(window) {
  panorama_ = new PanoramaView(window);
  panel_ = new PairPanel(window);
  // The panorama beside the log along the bottom, wide (panoramas are 4:1); the pair panel on the left.
  auto* pano_dock = new QDockWidget(tr("Panorama"), window);
  pano_dock->setObjectName("PanoramaViewDock");
  pano_dock->setWidget(panorama_);
  window->addDockWidget(Qt::BottomDockWidgetArea, pano_dock);
  if (auto* log = window->findChild<QDockWidget*>("LogDock")) {
    window->splitDockWidget(log, pano_dock, Qt::Horizontal);
    window->resizeDocks({log, pano_dock}, {1, 3}, Qt::Horizontal);
  }
  pano_dock_ = pano_dock;
  auto* pair_dock = new QDockWidget(tr("Pair registration"), window);
  pair_dock->setObjectName("PairPanelDock");
  pair_dock->setWidget(panel_);
  window->addDockWidget(Qt::LeftDockWidgetArea, pair_dock);

  ScanListPanel* list = window->scanList();
  connect(list, &QTableWidget::cellClicked, this, [this, list](int row, int) {
    if (QTableWidgetItem* item = list->item(row, 0)) ShowScan(item->text());
  });
  connect(list, &QTableWidget::currentCellChanged, this, [this, list](int row, int, int previous, int) {
    if (row == previous || !list->hasFocus()) return;  // keyboard navigation only; clicks come above
    if (QTableWidgetItem* item = list->item(row, 0)) ShowScan(item->text());
  });
  ConfusionPanel* confusion = window->confusionPanel();
  connect(confusion, &QTableWidget::cellClicked, this, [this, confusion](int row, int col) {
    const QTableWidgetItem* r = confusion->verticalHeaderItem(row);
    const QTableWidgetItem* c = confusion->horizontalHeaderItem(col);
    if (!r || !c) return;
    if (row == col) {
      ShowScan(r->text());
      return;
    }
    // Open the pair the way the project linked it; otherwise the row's scan is the parent.
    const io::Project& project = window_->project();
    for (const io::LinkRecord& l : project.links) {
      if (l.parent == c->text().toStdString() && l.child == r->text().toStdString()) {
        OpenPair(c->text(), r->text());
        return;
      }
    }
    OpenPair(r->text(), c->text());
  });
  window->networkPanel()->viewport()->installEventFilter(new NetworkClicks(window->networkPanel(), this));

  connect(window->jobs(), &JobRunner::Succeeded, this, &PairInspector::OnJobSucceeded);
  connect(window->jobs(), &JobRunner::Failed, this, &PairInspector::OnJobFailed);
  connect(window->document(), &ProjectDocument::Opened, this, &PairInspector::OnProjectOpened);
  connect(window->document(), &ProjectDocument::ScansChanged, this, &PairInspector::OnProjectOpened);
  connect(window->document(), &ProjectDocument::Changed, this, &PairInspector::OnProjectChanged);
  connect(panel_, &PairPanel::RunRequested, this, &PairInspector::RunPair);
  connect(panel_, &PairPanel::CancelRequested, this, &PairInspector::CancelPair);
  connect(panel_, &PairPanel::UseResultRequested, this, &PairInspector::UseResult);
  connect(panel_, &PairPanel::RefineRequested, this,
          [this] { window_->RefineScan(panel_->childScan(), panel_->parentScan()); });
  connect(panel_, &PairPanel::ShowProjectRequested, window, &MainWindow::Refresh);
}

void PairInspector::OnProjectChanged() {
  QStringList names;
  for (const io::ProjectScan& s : window_->project().scans) names << QString::fromStdString(s.name);
  panel_->SetScans(names);
}

void PairInspector::OnProjectOpened() {
  panoramas_.clear();
  last_pair_.reset();
  panorama_->ShowMessage(tr("Select a scan in the scan list, or a cell of the confusion matrix, to see its panorama."));
  panel_->ShowMessage("-", "");
}

void PairInspector::StartOrQueue(std::function<bool()>* slot, std::function<bool()> start) {
  if (window_->jobs()->busy()) {
    *slot = std::move(start);
    return;
  }
  *slot = nullptr;
  start();
}

void PairInspector::StartQueued() {
  if (!queued_pair_ && !queued_scan_) return;
  QTimer::singleShot(0, this, [this] {
    if (queued_pair_) {
      StartOrQueue(&queued_pair_, queued_pair_);
    } else if (queued_scan_) {
      StartOrQueue(&queued_scan_, queued_scan_);
    }
  });
}

template <typename T>
bool PairInspector::Start(const QString& title, JobRunner::Job<T> job, JobRunner::Done<T> done) {
  if (!window_->jobs()->Start<T>(title, std::move(job), std::move(done))) return false;
  running_ = title;
  return true;
}

bool PairInspector::ShowScan(const QString& name) {
  if (window_->project().FindScan(name.toStdString()) < 0) return false;
  if (auto it = panoramas_.find(name); it != panoramas_.end()) {
    panorama_->ShowScan(it->second);
    return true;
  }
  panorama_->ShowMessage(tr("Computing the panorama of %1…").arg(name));
  StartOrQueue(&queued_scan_, [this, name] {
    const int i = window_->project().FindScan(name.toStdString());
    if (i < 0) return false;
    // The full scan, read by the worker (the window keeps previews only).
    return Start<PanoramaImage>(
        tr("Panorama of %1").arg(name),
        [scans = window_->document()->FullScans(), i, name, options = window_->RegistrationOptions()](
            ProgressSink& progress, const CancelToken& cancel) -> Expected<PanoramaImage> {
          auto read = scans->Get(i);
          if (!read) return read.error();
          const Scan& scan = **read;
          progress.Report(0.1, "features of " + scan.name);
          Expected<ScanFeatures> features = Features(scan, options);
          if (!features) return features.error();
          if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "cancelled");
          return PanoramaImage{name, ReflectancePanorama(scan), features->keypoints};
        },
        [this](PanoramaImage& pano) {
          panoramas_[pano.scan] = pano;
          panorama_->ShowScan(pano);
          GrowPanoramaDockOnce();
        });
  });
  return true;
}

bool PairInspector::OpenPair(const QString& parent, const QString& child) {
  const io::Project& project = window_->project();
  if (parent == child || project.FindScan(parent.toStdString()) < 0 || project.FindScan(child.toStdString()) < 0)
    return false;
  panel_->SetPair(parent, child);
  if (const auto methods = LinkMethods(project, parent.toStdString(), child.toStdString()))
    panel_->SetMethods(methods->first, methods->second);
  // The evidence the project stores for the pair, shown as it is: Run registers it again (issue 14).
  const io::LinkRecord* stored = nullptr;
  for (const io::LinkRecord& l : project.links) {
    if (l.parent != parent.toStdString() || l.child != child.toStdString()) continue;
    if (!stored || io::IsTreeLink(l) || (stored->status == io::LinkStatus::kFailed && l.loop_check)) stored = &l;
  }
  if (stored) {
    const QString role = io::IsTreeLink(*stored) ? tr("the scan's link") : stored->loop_check ? tr("a loop check")
                                                                                             : tr("a failed attempt");
    panel_->ShowStoredLink(*stored, tr("stored: %1 of the last registration (Run registers the pair again)").arg(role));
  } else {
    panel_->ShowMessage(tr("not linked"), tr("the registration did not try this pair; Run registers it"));
  }
  const QString shown = child + " → " + parent;
  if (panoramas_.count(parent) && panoramas_.count(child))
    panorama_->ShowPair(panoramas_.at(parent), panoramas_.at(child), {}, {});
  else
    panorama_->ShowMessage(tr("%1: Run shows the matches of the two panoramas").arg(shown));
  return true;
}

bool PairInspector::RunPair() {
  const QString parent = panel_->parentScan(), child = panel_->childScan();
  const int p = window_->project().FindScan(parent.toStdString());
  const int c = window_->project().FindScan(child.toStdString());
  if (p < 0 || c < 0 || p == c) {
    panel_->ShowMessage(tr("not run"), tr("choose two different scans of the project"));
    return false;
  }
  panel_->ShowMessage(tr("waiting…"), window_->jobs()->busy() ? tr("starts when the running job ends") : "");
  panorama_->ShowMessage(tr("Registering %1 to %2…").arg(child, parent));
  StartOrQueue(&queued_pair_, [this, parent, child] {
    // Looked up again: a queued request starts after another job, which may have changed the project.
    const int p = window_->project().FindScan(parent.toStdString());
    const int c = window_->project().FindScan(child.toStdString());
    if (p < 0 || c < 0) {
      panel_->SetRunning(false);
      panel_->ShowMessage(tr("not run"), tr("the scans are no longer in the project"));
      return false;
    }
    pipeline::RegisterOptions options = window_->RegistrationOptions();
    options.coarse.method = panel_->coarseMethod();
    options.fine = panel_->fineMethod();
    const QString title = tr("Pair registration %1 → %2").arg(child, parent);
    const bool started = Start<PairJobResult>(
        title,
        [scans = window_->document()->FullScans(), p, c, options](
            ProgressSink& progress, const CancelToken& cancel) -> Expected<PairJobResult> {
          auto parent_read = scans->Get(p);
          if (!parent_read) return parent_read.error();
          auto child_read = scans->Get(c);
          if (!child_read) return child_read.error();
          const Scan &parent = **parent_read, &child = **child_read;
          Expected<pipeline::PairInspection> r = pipeline::InspectPair(parent, child, options, {}, progress, cancel);
          if (!r) return r.error();
          PairJobResult out;
          out.parent = {QString::fromStdString(parent.name), ReflectancePanorama(parent), r->parent_features.keypoints};
          out.child = {QString::fromStdString(child.name), ReflectancePanorama(child), r->child_features.keypoints};
          out.inspection = std::move(*r);
          return out;
        },
        [this](PairJobResult& pair) {
          panoramas_[pair.parent.scan] = pair.parent;
          panoramas_[pair.child.scan] = pair.child;
          last_pair_ = pair.inspection;
          panel_->SetRunning(false);
          panel_->ShowResult(pair.inspection);
          panorama_->ShowPair(pair.parent, pair.child, pair.inspection.matches, pair.inspection.coarse_inlier);
          GrowPanoramaDockOnce();
          ShowOverlay();
        });
    panel_->SetRunning(started);
    return started;
  });
  if (queued_pair_) panel_->SetRunning(true);  // waiting: Cancel withdraws the request
  return true;
}

void PairInspector::CancelPair() {
  if (queued_pair_) {
    panel_->SetRunning(false);
    panel_->ShowMessage(tr("cancelled"), tr("the project is unchanged"));
  }
  queued_pair_ = nullptr;
  if (running_.startsWith(tr("Pair registration"))) window_->jobs()->Cancel();
}

void PairInspector::OnJobSucceeded(const QString& title) {
  if (title == running_) running_.clear();  // its result went to the callback it was started with
  StartQueued();
}

void PairInspector::OnJobFailed(const QString& title, const QString& message, bool cancelled) {
  if (title == running_) {
    running_.clear();
    if (title.startsWith(tr("Pair registration"))) {
      panel_->SetRunning(false);
      panel_->ShowMessage(cancelled ? tr("cancelled") : tr("error"),
                          cancelled ? tr("the project is unchanged") : message);
      panorama_->ShowMessage(cancelled ? tr("Pair registration cancelled.") : message);
    } else {
      panorama_->ShowMessage(cancelled ? tr("Cancelled.") : message);
    }
  }
  StartQueued();
}

void PairInspector::GrowPanoramaDockOnce() {
  // The first panorama shown gets room (a pair stacks two); the user's layout wins after that.
  if (!grew_panorama_ && pano_dock_->height() < 300) window_->resizeDocks({pano_dock_}, {360}, Qt::Vertical);
  grew_panorama_ = true;
}

void PairInspector::ShowOverlay() {
  if (!last_pair_) return;
  const DistanceOverlay overlay = MakeDistanceOverlay(*last_pair_, kOverlayScaleMax_m);
  window_->view3d()->SetActors(overlay.clouds);
  window_->view3d()->renderer()->AddViewProp(overlay.legend);
  window_->view3d()->ResetCamera();  // renders with the legend
}

void PairInspector::UseResult() {
  if (last_pair_) window_->UsePairResult(last_pair_->result.link);
}

}  // namespace scanreg::ui
