#include "ui/merge_panel.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDoubleSpinBox>
#include <QFileDialog>
#include <QFileInfo>
#include <QFormLayout>
#include <QHBoxLayout>
#include <QLabel>
#include <QMessageBox>
#include <QPushButton>
#include <QSettings>
#include <QSignalBlocker>
#include <QSpinBox>
#include <QTimer>
#include <QVBoxLayout>

#include "core/merge/merge_estimate.h"
#include "core/merge/mesh_preview.h"
#include "core/merge/mesh_spill.h"
#include "core/pipeline/merge_scans.h"
#include "core/pipeline/scan_store.h"
#include "core/pipeline/project_scans.h"
#include "ui/app_settings.h"
#include "ui/job_runner.h"
#include "ui/main_window.h"
#include "ui/project_document.h"
#include "ui/scan_scene.h"

namespace scanreg::ui {
namespace {

struct ExportedMesh {
  QString path;
  std::size_t triangles = 0;
};

const QString kMergeTitle = QObject::tr("Merging the registered scans");
const QString kExportTitle = QObject::tr("Exporting the mesh");

}  // namespace

struct MergePanel::MergedMesh {
  std::shared_ptr<const merge::MeshSpill> mesh;  // the whole mesh, on disk
  std::shared_ptr<const merge::Mesh> preview;
  double preview_cell_m = 0.0;  // merge::MeshPreview::cell_m
  std::size_t scans = 0;
  double seconds = 0.0;
  merge::MergeMethod method = merge::MergeMethod::kTsdf;
  double voxel_m = 0.0;
  std::size_t moving_points = 0;
  bool removed_moving = false;
  std::size_t interpolated_vertices = 0;  // merge::MergeResult's
  bool fill_holes = false;
};

MergePanel::MergePanel(MainWindow* window, ScanScene* scene) : QWidget(window), window_(window), scene_(scene) {
  setObjectName("MergePanel");
  method_ = new QComboBox(this);
  method_->setObjectName("MergeMethod");
  method_->addItem(tr("Consensus (sub-voxel, most accurate)"), int(merge::MergeMethod::kConsensus));
  method_->addItem(tr("Maximum likelihood (Sagawa et al.)"), int(merge::MergeMethod::kMaximumLikelihood));
  method_->addItem(tr("TSDF (Curless–Levoy, faster)"), int(merge::MergeMethod::kTsdf));
  voxel_mm_ = new QDoubleSpinBox(this);
  voxel_mm_->setObjectName("MergeVoxel");
  voxel_mm_->setRange(1.0, 2000.0);
  voxel_mm_->setDecimals(1);
  voxel_mm_->setSuffix(tr(" mm"));
  voxel_mm_->setToolTip(tr("Edge of a voxel of the distance field: smaller is finer and slower."));
  smooth_ = new QSpinBox(this);
  smooth_->setObjectName("MergeSmoothing");
  smooth_->setRange(0, 20);
  smooth_->setSuffix(tr(" passes"));
  smooth_->setToolTip(tr("Passes of a 3×3×3 mean filter over the distance field (0: none)."));
  max_range_m_ = new QDoubleSpinBox(this);
  max_range_m_->setObjectName("MergeMaxRange");
  max_range_m_->setRange(0.0, 10000.0);
  max_range_m_->setDecimals(1);
  max_range_m_->setSuffix(tr(" m"));
  max_range_m_->setSpecialValueText(tr("all returns"));
  max_range_m_->setToolTip(tr("Returns farther from their scanner are left out (sparse, noisy far returns)."));
  keep_pieces_ = new QCheckBox(tr("Keep small disconnected pieces"), this);
  keep_pieces_->setObjectName("MergeKeepPieces");
  fill_holes_ = new QCheckBox(tr("Fill holes (interpolated surface marked)"), this);
  fill_holes_->setObjectName("MergeFillHoles");
  fill_holes_->setToolTip(tr("The consensus leaves a hole where the samples lie farther apart than the voxel; filled, "
                             "the surface there comes from the nearest measurement. Every exported PLY vertex holds "
                             "its distance to the nearest scan point (scalar_gap; \"gap\" in CloudCompare)."));
  keep_moving_ = new QCheckBox(tr("Keep moving objects (vehicles, people)"), this);
  keep_moving_->setObjectName("MergeKeepMoving");
  keep_moving_->setToolTip(tr("Points one scanner saw where another saw through are moving objects; by default "
                              "they are left out so the mesh has no ghosts of passing traffic."));

  auto* form = new QFormLayout;
  form->addRow(tr("Method"), method_);
  form->addRow(tr("Voxel"), voxel_mm_);
  form->addRow(tr("Smoothing"), smooth_);
  form->addRow(tr("Max range"), max_range_m_);
  form->addRow(QString(), keep_pieces_);
  form->addRow(QString(), fill_holes_);
  form->addRow(QString(), keep_moving_);

  run_ = new QPushButton(tr("Merge registered scans"), this);
  run_->setObjectName("MergeRun");
  export_ = new QPushButton(tr("Export mesh…"), this);
  export_->setObjectName("MergeExport");
  auto* buttons = new QHBoxLayout;
  buttons->addWidget(run_);
  buttons->addWidget(export_);

  show_scans_ = new QCheckBox(tr("Scans"), this);
  show_scans_->setObjectName("ShowScans");
  show_scans_->setChecked(scene_->showScans());
  show_mesh_ = new QCheckBox(tr("Mesh"), this);
  show_mesh_->setObjectName("ShowMesh");
  show_mesh_->setChecked(scene_->showMesh());
  auto* show = new QHBoxLayout;
  show->addWidget(new QLabel(tr("Show in 3D view:"), this));
  show->addWidget(show_scans_);
  show->addWidget(show_mesh_);
  show->addStretch();

  summary_ = new QLabel(tr("No mesh yet: register the scans, then merge."), this);
  summary_->setObjectName("MergeSummary");
  summary_->setWordWrap(true);

  estimate_ = new QLabel(this);
  estimate_->setObjectName("MergeEstimate");
  estimate_->setWordWrap(true);
  estimate_->setToolTip(tr("What the merge will take with these options, counted from the registered scans before "
                           "it starts; a merge beyond three quarters of this computer's memory is refused."));
  estimate_timer_ = new QTimer(this);
  estimate_timer_->setSingleShot(true);
  estimate_timer_->setInterval(300);  // after the user stops turning a spin box
  estimator_ = new JobRunner(this);   // its own worker: the estimate neither waits for nor blocks a job

  auto* layout = new QVBoxLayout(this);
  layout->addLayout(form);
  layout->addWidget(estimate_);
  layout->addLayout(buttons);
  layout->addLayout(show);
  layout->addWidget(summary_);
  layout->addStretch();

  // Defaults from MergeOptions, then what the user chose last time.
  const merge::MergeOptions defaults;
  QSettings settings;
  merge::MergeOptions options = defaults;
  options.method = static_cast<merge::MergeMethod>(settings.value("merge/method", int(defaults.method)).toInt());
  options.voxel_m = settings.value("merge/voxel_m", defaults.voxel_m).toDouble();
  options.smooth_iterations = settings.value("merge/smooth_iterations", defaults.smooth_iterations).toInt();
  options.max_range_m = settings.value("merge/max_range_m", defaults.max_range_m).toDouble();
  options.remove_small_pieces = settings.value("merge/remove_small_pieces", defaults.remove_small_pieces).toBool();
  options.remove_moving = settings.value("merge/remove_moving", defaults.remove_moving).toBool();
  options.fill_holes = settings.value("merge/fill_holes", defaults.fill_holes).toBool();
  SetOptions(options.Validate() ? options : defaults);
  voxel_chosen_ = false;  // remembered from another project: sized to the next one

  connect(run_, &QPushButton::clicked, this, &MergePanel::Run);
  connect(export_, &QPushButton::clicked, this, &MergePanel::ChooseExportFile);
  connect(show_scans_, &QCheckBox::toggled, scene_, &ScanScene::SetShowScans);
  connect(show_mesh_, &QCheckBox::toggled, scene_, &ScanScene::SetShowMesh);
  connect(window_->jobs(), &JobRunner::Succeeded, this, &MergePanel::UpdateButtons);
  connect(window_->jobs(), &JobRunner::Started, this, &MergePanel::UpdateButtons);
  connect(window_->jobs(), &JobRunner::Failed, this, &MergePanel::UpdateButtons);
  connect(estimate_timer_, &QTimer::timeout, this, &MergePanel::UpdateEstimate);
  auto counted = [this] {  // options changed while it counted: count again
    if (estimate_again_) estimate_again_ = false, estimate_timer_->start();
  };
  connect(estimator_, &JobRunner::Succeeded, this, counted);
  connect(estimator_, &JobRunner::Failed, this, counted);
  auto later = [this] { estimate_timer_->start(); };
  connect(method_, qOverload<int>(&QComboBox::currentIndexChanged), this, later);
  connect(voxel_mm_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, [this, later] {
    voxel_chosen_ = true;  // the panel's own sizing sets it with signals blocked
    sized_sigma_m_ = 0;
    later();
  });
  connect(window_->document(), &ProjectDocument::Opened, this, [this] {
    voxel_chosen_ = false;
    sized_sigma_m_ = 0;
  });
  connect(max_range_m_, qOverload<double>(&QDoubleSpinBox::valueChanged), this, later);
  connect(keep_moving_, &QCheckBox::toggled, this, later);
  connect(window_->document(), &ProjectDocument::Changed, this, later);
  connect(window_->document(), &ProjectDocument::PosesChanged, this, [this] {
    estimate_timer_->start();
    if (!mesh_) return;
    ClearMesh();
    summary_->setText(tr("The registration changed: merge again for a mesh that matches it."));
  });
  UpdateButtons();
}

void MergePanel::SetShown(bool shown) {
  shown_ = shown;
  if (shown_ && estimate_stale_) estimate_timer_->start();
}

namespace {

// What the estimate is counted from, copied for the worker: the registered scans' previews (points,
// validity, listed points, grid and pose only), each standing for its scan (stride^2 points a preview point).
struct EstimateInput {
  std::vector<Scan> scans;
  std::vector<int> strides;
  merge::MergeOptions options;
  bool size_voxel = false;  // the voxel is sized to the project (pipeline::SizedMergeOptions)
};

struct EstimateOutput {
  merge::MergeOptions options;  // with the sized voxel, to the voxel box's 0.1 mm
  merge::MergeEstimate estimate;
  Status fits;
};

EstimateOutput CountEstimate(const EstimateInput& in) {
  std::vector<const Scan*> scans;
  for (const Scan& s : in.scans) scans.push_back(&s);
  EstimateOutput out;
  out.options = in.options;
  if (in.size_voxel) {  // a default that finishes in about a minute on this project
    merge::MergeOptions base = in.options;
    base.voxel_m = merge::MergeOptions().voxel_m;
    base.sigma_m = merge::MergeOptions().sigma_m;
    const merge::MergeOptions sized = pipeline::SizedMergeOptions(scans, base, 60.0, nullptr, in.strides);
    out.options.voxel_m = std::clamp(std::round(sized.voxel_m * 1e4) / 1e4, 1e-3, 2.0);
    out.options.sigma_m = sized.sigma_m;
  }
  out.fits = merge::CheckMergeFits(scans, out.options, &out.estimate, in.strides, /*mesh_on_disk=*/true);
  return out;
}

}  // namespace

void MergePanel::UpdateEstimate() {
  estimate_stale_ = !shown_;
  if (estimate_stale_) {  // what it said no longer holds
    ++estimate_generation_;
    estimate_->clear();
    return;
  }
  if (estimator_->busy()) {  // the running count is of older inputs: counted again when it ends
    ++estimate_generation_;
    estimate_again_ = true;
    return;
  }
  auto input = std::make_shared<EstimateInput>();
  input->options = Options();
  input->size_voxel = !voxel_chosen_;
  for (std::size_t i = 0; i < window_->previews().size() && i < window_->project().scans.size(); ++i) {
    if (!window_->project().scans[i].registered) continue;
    const Scan& preview = window_->previews()[i].scan;
    Scan& copy = input->scans.emplace_back();
    copy.name = preview.name;
    copy.rows = preview.rows, copy.cols = preview.cols;
    copy.points = preview.points;
    copy.valid = preview.valid;
    copy.list_points = preview.list_points;  // merged as discs: counted too
    copy.single_viewpoint = preview.single_viewpoint;
    copy.world_from_scan = preview.world_from_scan;
    input->strides.push_back(window_->previews()[i].stride);
  }
  ++estimate_generation_;
  if (input->scans.empty() || !input->options.Validate()) {
    estimate_->clear();
    return;
  }
  // The last estimate stays, greyed, while the new one is counted (seconds on 100 stations).
  estimate_->setStyleSheet("color: gray;");
  if (estimate_->text().isEmpty()) estimate_->setText(tr("Counting what the merge will take…"));
  const int generation = estimate_generation_;
  estimator_->Start<EstimateOutput>(
      tr("Merge estimate"),
      [input](ProgressSink&, const CancelToken&) -> Expected<EstimateOutput> { return CountEstimate(*input); },
      [this, generation, scans = input->scans.size(), sized = input->size_voxel](EstimateOutput& out) {
        // Inputs changed meanwhile: counted again when this count ends (or when the panel is shown).
        if (generation != estimate_generation_) return;
        if (sized && !voxel_chosen_) {
          const QSignalBlocker quiet(voxel_mm_);  // the estimate below is already of this voxel
          voxel_mm_->setValue(out.options.voxel_m * 1000.0);
          sized_sigma_m_ = out.options.sigma_m;
        }
        if (!out.fits) {
          estimate_->setText(QString::fromStdString(out.fits.error().message));
          estimate_->setStyleSheet("color: #b00000;");
          return;
        }
        estimate_->setStyleSheet(QString());
        estimate_->setText(tr("Estimate for %n scan(s): ", "", int(scans)) +
                           QString::fromStdString(out.estimate.Describe()) +
                           (voxel_chosen_ ? QString()
                                          : tr(" — voxel and range noise (%1 mm) sized for this project (set the voxel "
                                               "to choose your own)")
                                                .arg(out.options.sigma_m * 1000.0, 0, 'g', 3)));
      });
}

merge::MergeOptions MergePanel::Options() const {
  merge::MergeOptions options;
  options.method = static_cast<merge::MergeMethod>(method_->currentData().toInt());
  options.voxel_m = voxel_mm_->value() / 1000.0;
  if (!voxel_chosen_ && sized_sigma_m_ > 0) options.sigma_m = sized_sigma_m_;  // sized with the voxel
  options.smooth_iterations = smooth_->value();
  options.max_range_m = max_range_m_->value();
  options.remove_small_pieces = !keep_pieces_->isChecked();
  options.remove_moving = !keep_moving_->isChecked();
  options.fill_holes = fill_holes_->isChecked();
  return options;
}

void MergePanel::SetOptions(const merge::MergeOptions& options) {
  method_->setCurrentIndex(method_->findData(int(options.method)));
  voxel_mm_->setValue(options.voxel_m * 1000.0);
  smooth_->setValue(options.smooth_iterations);
  max_range_m_->setValue(options.max_range_m);
  keep_pieces_->setChecked(!options.remove_small_pieces);
  keep_moving_->setChecked(!options.remove_moving);
  fill_holes_->setChecked(options.fill_holes);
}

void MergePanel::SaveOptions() const {
  const merge::MergeOptions options = Options();
  QSettings settings;
  settings.setValue("merge/method", int(options.method));
  settings.setValue("merge/voxel_m", options.voxel_m);
  settings.setValue("merge/smooth_iterations", options.smooth_iterations);
  settings.setValue("merge/max_range_m", options.max_range_m);
  settings.setValue("merge/remove_small_pieces", options.remove_small_pieces);
  settings.setValue("merge/remove_moving", options.remove_moving);
  settings.setValue("merge/fill_holes", options.fill_holes);
}

bool MergePanel::Run() {
  if (window_->jobs()->busy()) return false;
  const merge::MergeOptions options = Options();
  if (Status s = options.Validate(); !s) {
    ShowError(tr("Cannot merge"),
              QString::fromStdString(s.error().message) + tr("\nChange the option and merge again."));
    return false;
  }
  SaveOptions();
  std::vector<int> registered;  // read in full by the job
  for (std::size_t i = 0; i < window_->project().scans.size(); ++i)
    if (window_->project().scans[i].registered) registered.push_back(static_cast<int>(i));
  if (registered.empty()) {
    ShowError(tr("Nothing to merge"),
              window_->project().scans.empty()
                  ? tr("No project is open. Open a project (File → Open project…), register it, then merge.")
                  : tr("No scan is registered yet. Register the project first (Registration → Register all "
                       "scans, Ctrl+R), then merge."));
    return false;
  }
  return window_->jobs()->Start<MergedMesh>(
      kMergeTitle,
      [project = window_->project(), registered = std::move(registered), options, preview_triangles = preview_triangles_](
          ProgressSink& progress, const CancelToken& cancel) -> Expected<MergedMesh> {
        // The mesh goes to temporary files in the project's cache folder as the tiles are meshed (as
        // the CLI's does): the desktop holds a preview of it, within preview_triangles, and Export
        // streams the whole mesh from there. The files go with the mesh (next merge, new project, exit).
        std::filesystem::path dir = pipeline::ProjectCacheDir(project);
        std::error_code failed;
        std::filesystem::create_directories(dir, failed);
        auto spill = merge::MeshSpill::Create(dir);
        if (!spill) return spill.error();
        // Scans read from their files as the merge needs them, a quarter of the RAM at most resident.
        Expected<merge::MergeResult> r = pipeline::MergeProjectScans(
            project, registered, options, pipeline::DefaultMemoryBudget(), progress, cancel, spill->get());
        if (!r) return r.error();
        progress.Report(1.0, "Preparing the mesh for the 3D view");
        auto preview = merge::PreviewMesh(**spill, preview_triangles, options.voxel_m, cancel);
        if (!preview) return preview.error();
        return MergedMesh{std::shared_ptr<const merge::MeshSpill>(std::move(*spill)),
                          std::make_shared<const merge::Mesh>(std::move(preview->mesh)),
                          preview->cell_m,
                          r->scans,
                          r->seconds,
                          options.method,
                          options.voxel_m,
                          r->moving_points,
                          options.remove_moving,
                          r->interpolated_vertices,
                          options.fill_holes};
      },
      [this](MergedMesh& merged) { OnMerged(merged); });
}

bool MergePanel::ExportMesh(const QString& path) {
  if (!mesh_ || window_->jobs()->busy()) return false;
  return window_->jobs()->Start<ExportedMesh>(
      kExportTitle,
      [mesh = mesh_, path](ProgressSink& progress, const CancelToken&) -> Expected<ExportedMesh> {
        progress.Report(0.0, "Writing " + path.toStdString());
        if (Status s = pipeline::WriteMesh(path.toStdString(), *mesh); !s) return s.error();
        return ExportedMesh{path, mesh->triangle_count()};
      },
      [this](ExportedMesh& exported) {
        summary_->setText(tr("Exported %L1 triangles to %2.").arg(exported.triangles).arg(exported.path));
      });
}

void MergePanel::ChooseExportFile() {
  if (!mesh_) return;
  QString filter;
  QString path = QFileDialog::getSaveFileName(this, tr("Export mesh"), LastDir() + "/merged.ply",
                                              tr("PLY mesh (*.ply);;Wavefront OBJ (*.obj);;STL (*.stl)"), &filter);
  if (path.isEmpty()) return;
  const QString suffix = QFileInfo(path).suffix().toLower();
  if (suffix != "ply" && suffix != "obj" && suffix != "stl") {
    path += filter.contains("*.obj") ? ".obj" : filter.contains("*.stl") ? ".stl" : ".ply";
  }
  RememberDir(path);
  ExportMesh(path);
}

void MergePanel::OnMerged(const MergedMesh& merged) {
  mesh_ = merged.mesh;
  preview_ = merged.preview;
  scene_->SetMesh(preview_);
  QString text = tr("%L1 triangles, %L2 vertices\nfrom %3 scans (%4, %5 mm voxels) in %6 s.")
                     .arg(mesh_->triangle_count())
                     .arg(mesh_->vertex_count())
                     .arg(merged.scans)
                     .arg(merged.method == merge::MergeMethod::kTsdf        ? tr("TSDF")
                          : merged.method == merge::MergeMethod::kConsensus ? tr("consensus")
                                                                            : tr("maximum likelihood"))
                     .arg(merged.voxel_m * 1000.0, 0, 'f', 1)
                     .arg(merged.seconds, 0, 'f', 1);
  if (merged.preview_cell_m > 0.0)
    text += tr("\nShown simplified to %L1 triangles (vertices joined on %2 mm cells); Export writes the whole mesh.")
                .arg(preview_->triangles.size())
                .arg(merged.preview_cell_m * 1000.0, 0, 'f', 0);
  if (merged.removed_moving)
    text += tr("\n%L1 points in another scanner's free space left out (moving objects, stray returns).")
                .arg(merged.moving_points);
  if (mesh_->vertex_count() > 0)
    text += tr("\n%1 % of the vertices lie over 1.5 voxels from every scan point%2: interpolated.")
                .arg(100.0 * double(merged.interpolated_vertices) / double(mesh_->vertex_count()), 0, 'f', 1)
                .arg(merged.fill_holes ? tr(" or on a filled hole") : QString());
  if (mesh_->coloured()) text += tr("\nColoured by the scanners' colour.");
  summary_->setText(text);
}

void MergePanel::ClearMesh() {
  mesh_.reset();
  preview_.reset();
  scene_->SetMesh(nullptr);
  UpdateButtons();
}

void MergePanel::UpdateButtons() {
  const bool idle = !window_->jobs()->busy();
  run_->setEnabled(idle);
  export_->setEnabled(idle && mesh_ != nullptr);
}

void MergePanel::ShowError(const QString& title, const QString& message) {
  auto* box = new QMessageBox(QMessageBox::Warning, title, message, QMessageBox::Ok, this);
  box->setAttribute(Qt::WA_DeleteOnClose);
  box->setObjectName("ErrorDialog");
  box->open();  // window-modal, does not block the event loop
}

}  // namespace scanreg::ui
