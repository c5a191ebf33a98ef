// Export section (issue 7): export-clouds of registered scans in PTX, PLY and E57 with the poses kept
// in the header or applied to the points, PCL's binary PLY writer on the same world-coordinate points
// as the baseline; and the registration report of an 11-scan project (W's size of project).
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "core/io/ply.h"
#include "core/pipeline/export_clouds.h"
#include "core/report/report.h"
#include "tests/bench/bench_table.h"
#include "tests/io/io_test_util.h"

namespace scanreg::bench {
namespace {

double FolderMiB(const std::filesystem::path& dir) {
  double bytes = 0;
  for (const auto& f : std::filesystem::directory_iterator(dir)) bytes += double(f.file_size());
  return bytes / (1 << 20);
}

Eigen::Isometry3d StationPose(int i) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(0.4 * i, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(5.0 * i, 0.3 * i, 0.02 * i);
  return t;
}

// 11 registered scans in a chain with a confusion matrix, links and coarse / reference poses (a few
// mm and hundredths of a degree apart), as a registration leaves them; the scan files are dummies.
io::Project ReportProject(const std::filesystem::path& dir) {
  io::Project p;
  p.file = dir / "report.scanreg.json";
  const int n = 11;
  std::mt19937 rng(3);
  std::normal_distribution<double> mm(0.0, 0.004);
  p.confusion = Eigen::MatrixXi::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    io::ProjectScan s;
    s.name = (i < 9 ? "s0" : "s") + std::to_string(i + 1);
    s.path = dir / (s.name + ".ptx");
    s.registered = true;
    s.world_from_scan = StationPose(i);
    s.reference_world_from_scan = StationPose(i) * Eigen::Translation3d(mm(rng), mm(rng), mm(rng));
    s.coarse_world_from_scan = StationPose(i) * Eigen::Translation3d(5 * mm(rng), 5 * mm(rng), 5 * mm(rng));
    p.scans.push_back(s);
    p.confusion_scans.push_back(s.name);
    for (int j = 0; j < n; ++j) p.confusion(i, j) = i == j ? 5000 + 200 * i : 700 / (1 + std::abs(i - j) * 2);
    if (i > 0) {
      io::LinkRecord l;
      l.parent = p.scans[i - 1].name;
      l.child = s.name;
      l.status = i % 4 == 0 ? io::LinkStatus::kWeak : io::LinkStatus::kOk;
      l.matches = 200;
      l.reliable = 90;
      l.ransac_inliers = 40;
      l.consistent = 30;
      l.rms_m = 0.011;
      l.overlap = 0.7;
      p.links.push_back(l);
    }
  }
  p.root = p.scans[0].name;
  return p;
}

}  // namespace

void RunExportBench(Table& table, bool quick) {
  const int cols = quick ? 750 : 3000, rows = quick ? 188 : 750, scans = quick ? 2 : 3;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("scanreg-bench-export-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir / "in");
  NullProgress progress;
  CancelToken cancel;
  io::Project project;
  project.file = dir / "in" / "project.scanreg.json";
  double valid = 0;
  for (int i = 0; i < scans; ++i) {
    io::ProjectScan s;
    s.name = "s0" + std::to_string(i + 1);
    s.path = dir / "in" / (s.name + ".ply");
    s.world_from_scan = StationPose(i);
    s.registered = true;
    const Scan scan = test::MakeRoomScan(rows, cols, s.name);
    valid += double(scan.CountValid());
    if (Status w = io::WritePly(s.path, scan, progress, cancel); !w) {
      table.Add({"export", "input scans", 0.0, "", "failed: " + w.error().ToString()});
      std::filesystem::remove_all(dir);
      return;
    }
    project.scans.push_back(s);
  }
  const std::string size = std::to_string(scans) + " x " + std::to_string(cols) + "x" + std::to_string(rows);
  for (const char* format : {"ptx", "ply", "e57"}) {
    for (bool apply : {false, true}) {
      pipeline::ExportCloudsOptions options;
      options.dir = dir / (std::string(format) + (apply ? "-applied" : "-kept"));
      options.format = format;
      options.apply_poses = apply;
      Expected<std::vector<pipeline::ExportedScan>> out = MakeError(ErrorCode::kFailed, "not run");
      const double s = Seconds([&] { out = pipeline::ExportClouds(project, options, progress, cancel); });
      const std::string what = std::string("export-clouds ") + format + (apply ? " applied " : " kept ") + size;
      if (!out) {
        table.Add({"export", what, 0.0, "", "failed: " + out.error().ToString()});
        continue;
      }
      char note[96];
      std::snprintf(note, sizeof note, "%.1f MiB written, incl. reading the PLY inputs", FolderMiB(options.dir));
      table.Add({"export", what + " (scanreg)", valid / s / 1e6, "M points/s", note});
    }
  }
  // Baseline: PCL's binary PLY writer on the same world-coordinate points (no grid), beside our PLY
  // writer alone on them (the export rows above also read each input scan).
  double pcl_s = 0, ours_s = 0;
  for (int i = 0; i < scans; ++i) {
    Scan scan = test::MakeRoomScan(rows, cols, "pcl");
    pcl::PointCloud<pcl::PointXYZI> cloud;
    const Eigen::Isometry3f t = project.scans[i].world_from_scan.cast<float>();
    for (std::size_t k = 0; k < scan.size(); ++k) {
      if (!scan.valid[k]) continue;
      const Eigen::Vector3f p = t * scan.points[k];
      pcl::PointXYZI q;
      q.x = p.x();
      q.y = p.y();
      q.z = p.z();
      q.intensity = scan.reflectance[k];
      cloud.push_back(q);
    }
    const std::string file = (dir / ("pcl" + std::to_string(i) + ".ply")).string();
    pcl_s += Seconds([&] { pcl::io::savePLYFileBinary(file, cloud); });
    for (std::size_t k = 0; k < scan.size(); ++k)
      if (scan.valid[k]) scan.points[k] = t * scan.points[k];
    scan.angles = AngularGrid{};
    const auto ours = dir / ("ours" + std::to_string(i) + ".ply");
    ours_s += Seconds([&] { (void)io::WritePly(ours, scan, progress, cancel); });
  }
  table.Add({"export", "PLY applied " + size + " (scanreg WritePly)", valid / ours_s / 1e6, "M points/s",
             "writing only, with the range grid, incl. fsync"});
  table.Add({"export", "PLY applied " + size + " (PCL savePLYFileBinary)", valid / pcl_s / 1e6, "M points/s",
             "baseline: writing only, no fsync"});

  const io::Project report_project = ReportProject(dir);
  Expected<std::filesystem::path> index = MakeError(ErrorCode::kFailed, "not run");
  const double report_s =
      Seconds([&] { index = report::WriteReport(report_project, dir / "report", progress, cancel); });
  table.Add({"export", "report of an 11-scan project (HTML + 3 PNG)", index ? report_s * 1e3 : 0.0, "ms",
             index ? "confusion, network, error chart, tables" : "failed: " + index.error().ToString()});
  std::filesystem::remove_all(dir);
}

}  // namespace scanreg::bench
