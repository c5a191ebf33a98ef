// Georeferencing section (issue 15):
//  (a) sphere targets found per scan at 3000x750 (0.12°) with 2 mm noise, against PCL's RANSAC with
//      the sphere model (SACMODEL_SPHERE, radius limits, then its least-squares refinement), the
//      spheres extracted one after another from the same cloud;
//  (b) centre error against range (5 to 30 m) at 0.12° and 0.06° steps;
//  (c) the adjustment of 100 stations with 50 targets (links, observations, control, blunder test);
//  (d) checkerboards on walls: detection time per 3000x750 scan and centre error against range (5
//      to 30 m, boards turned 30° from the line of sight) at 0.12° and 0.06° steps.
#include <pcl/ModelCoefficients.h>
#include <pcl/filters/extract_indices.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <random>

#include "core/georef/checker_targets.h"
#include "core/georef/georeference.h"
#include "core/georef/sphere_targets.h"
#include "core/simulate/scanner.h"
#include "core/simulate/scene.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {
namespace {

const char* kSection = "georef";
constexpr double kRadius = 0.0725;

// Ground, a wall, a pole of the spheres' radius, and spheres on tripods at the given centres.
Scene Yard(const std::vector<Eigen::Vector3d>& spheres) {
  Scene scene;
  const int grey = scene.AddTexture(SurfaceTexture::Uniform(0.4f)), white = scene.AddTexture(SurfaceTexture::Uniform(0.85f));
  scene.AddRectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 80, 80, grey);
  scene.AddRectangle(Eigen::Vector3d(35, 0, 3), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 40, 3, grey);
  scene.AddCylinder({7.0, -4.0}, kRadius, 0.0, 2.5, grey);
  for (const Eigen::Vector3d& c : spheres) {
    scene.AddSphere(c, kRadius, white);
    scene.AddCylinder({c.x(), c.y()}, 0.012, 0.0, c.z() - 0.06, grey);
  }
  scene.Build();
  return scene;
}

Scan ScanOf(const Scene& scene, int cols, int rows, double el_min, double el_max) {
  ScannerOptions o;
  o.cols = cols;
  o.rows = rows;
  o.elevation_min_deg = el_min;
  o.elevation_max_deg = el_max;
  o.range_noise_m = 0.002;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 1.6);
  NullProgress progress;
  CancelToken cancel;
  return SimulateScan(scene, pose, o, "yard", progress, cancel).value();
}

// The error (mm) of the found sphere nearest to `truth` (scanner frame), or -1 when none is near.
double ErrorMm(const std::vector<Eigen::Vector3d>& found, const Eigen::Vector3d& truth) {
  double best = 1e9;
  for (const Eigen::Vector3d& f : found) best = std::min(best, (f - truth).norm());
  return best < 0.05 ? best * 1000 : -1;
}

void DetectionSection(Table& table) {
  const std::vector<Eigen::Vector3d> spheres{{5.0, 0.6, 1.4}, {-3.0, 9.5, 1.3}, {2.0, -14.8, 1.6}, {-17, -12, 1.5}};
  const Scene scene = Yard(spheres);
  const Scan scan = ScanOf(scene, 3000, 750, -40, 50);
  std::vector<Eigen::Vector3d> ours;
  CancelToken cancel;
  georef::SphereTargetOptions options;
  const double t_ours = Seconds([&] {
    const std::vector<georef::DetectedSphere> detected = georef::DetectSphereTargets(scan, options, cancel).value();
    for (const georef::DetectedSphere& s : detected) ours.push_back(s.center);
  });
  // PCL: the sphere model with radius limits on the whole cloud, extracting each sphere in turn.
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) cloud->push_back(pcl::PointXYZ(scan.points[i].x(), scan.points[i].y(), scan.points[i].z()));
  std::vector<Eigen::Vector3d> pcl_found;
  const double t_pcl = Seconds([&] {
    pcl::SACSegmentation<pcl::PointXYZ> seg;
    seg.setModelType(pcl::SACMODEL_SPHERE);
    seg.setMethodType(pcl::SAC_RANSAC);
    seg.setOptimizeCoefficients(true);
    seg.setRadiusLimits(0.95 * kRadius, 1.05 * kRadius);
    seg.setDistanceThreshold(0.004);
    seg.setMaxIterations(20000);
    pcl::PointCloud<pcl::PointXYZ>::Ptr rest(new pcl::PointCloud<pcl::PointXYZ>(*cloud));
    for (std::size_t k = 0; k < spheres.size(); ++k) {
      pcl::ModelCoefficients coefficients;
      pcl::PointIndices::Ptr inliers(new pcl::PointIndices);
      seg.setInputCloud(rest);
      seg.segment(*inliers, coefficients);
      if (inliers->indices.size() < 10 || coefficients.values.size() < 4) break;
      pcl_found.emplace_back(coefficients.values[0], coefficients.values[1], coefficients.values[2]);
      pcl::ExtractIndices<pcl::PointXYZ> extract;
      extract.setInputCloud(rest);
      extract.setIndices(inliers);
      extract.setNegative(true);
      pcl::PointCloud<pcl::PointXYZ>::Ptr next(new pcl::PointCloud<pcl::PointXYZ>);
      extract.filter(*next);
      rest = next;
    }
  });
  int ours_right = 0, pcl_right = 0;
  for (const Eigen::Vector3d& s : spheres) {
    const Eigen::Vector3d local = s - Eigen::Vector3d(0, 0, 1.6);
    ours_right += ErrorMm(ours, local) >= 0;
    pcl_right += ErrorMm(pcl_found, local) >= 0;
  }
  const std::string size = "3000x750, 2 mm noise, 4 spheres 5-21 m";
  table.Add({kSection, "spheres found per scan: scanreg", t_ours, "s", size + ": " + std::to_string(ours_right) + " of 4 right, " +
                                                                       std::to_string(ours.size() - ours_right) + " false"});
  table.Add({kSection, "spheres found per scan: PCL RANSAC SACMODEL_SPHERE", t_pcl, "s",
             "same scan, 20000 iterations a sphere: " + std::to_string(pcl_right) + " of 4 right, " +
                 std::to_string(pcl_found.size() - pcl_right) + " false"});
}

void AccuracySection(Table& table, bool quick) {
  const std::vector<double> ranges = quick ? std::vector<double>{5, 15} : std::vector<double>{5, 10, 15, 20, 25, 30};
  std::vector<Eigen::Vector3d> spheres;
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    const double a = 0.9 * k + 0.3;  // spread in azimuth so that none hides another
    spheres.emplace_back(ranges[k] * std::cos(a), ranges[k] * std::sin(a), 1.5);
  }
  const Scene scene = Yard(spheres);
  for (const auto& [cols, rows, label] : {std::tuple{3000, 334, "0.12°"}, std::tuple{6000, 667, "0.06°"}}) {
    const Scan scan = ScanOf(scene, cols, rows, -20, 20);
    CancelToken cancel;
    std::vector<Eigen::Vector3d> found;
    const std::vector<georef::DetectedSphere> detected = georef::DetectSphereTargets(scan, {}, cancel).value();
    for (const georef::DetectedSphere& s : detected) found.push_back(s.center);
    for (std::size_t k = 0; k < ranges.size(); ++k) {
      const double e = ErrorMm(found, spheres[k] - Eigen::Vector3d(0, 0, 1.6));
      table.Add({kSection, "sphere centre error at " + std::to_string(int(ranges[k])) + " m, " + label, e, "mm",
                 e < 0 ? "not found (too few points at this range and step)" : "145 mm sphere, 2 mm noise"});
    }
  }
}

void AdjustmentSection(Table& table, bool quick) {
  const int stations = quick ? 20 : 100, n_targets = quick ? 10 : 50;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Eigen::Isometry3d> truth, registered;
  for (int i = 0; i < stations; ++i) {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.translation() = Eigen::Vector3d(512000 + 8.0 * i, 5400000 + 0.5 * n(rng), 100 + 1.7);
    p.linear() = Eigen::AngleAxisd(n(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    truth.push_back(p);
  }
  std::vector<georef::ScanLink> links;
  registered.push_back(Eigen::Isometry3d::Identity());
  for (int i = 1; i < stations; ++i) {
    Eigen::Isometry3d jitter = Eigen::Isometry3d::Identity();
    jitter.translation() = 0.002 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    jitter.linear() = Eigen::AngleAxisd(1e-4 * n(rng), Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized()).toRotationMatrix();
    const Eigen::Isometry3d measured = truth[i - 1].inverse() * truth[i] * jitter;
    links.push_back({i - 1, i, measured});
    registered.push_back(registered.back() * measured);
  }
  std::vector<Eigen::Vector3d> targets;
  const double span = 8.0 * (stations - 1);
  for (int k = 0; k < n_targets; ++k)
    targets.emplace_back(512000 + span * k / (n_targets - 1) + 0.3 * n(rng), 5400000 + (k % 2 ? 3.0 : -3.0) + n(rng),
                         100 + 1.3 + 0.2 * n(rng));
  std::vector<georef::TargetObservation> observations;
  for (int i = 0; i < stations; ++i)
    for (const Eigen::Vector3d& x : targets)
      if ((x - truth[i].translation()).norm() < 20)
        observations.push_back({i, truth[i].inverse() * x + 0.001 * Eigen::Vector3d(n(rng), n(rng), n(rng)), 0.001, {}});
  std::vector<io::ControlPoint> control;
  for (int k = 0; k < n_targets; k += 5) {
    io::ControlPoint c;
    c.name = "CP" + std::to_string(k);
    c.position = targets[k] + 0.002 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    c.sigma_m = 0.002;
    control.push_back(c);
  }
  georef::GeorefOptions options;
  options.levelled_sigma_rad = 5e-5;
  CancelToken cancel;
  Expected<georef::GeorefResult> result = MakeError(ErrorCode::kFailed, "not run");
  const double t = Seconds([&] { result = georef::Georeference(registered, links, observations, control, options, cancel); });
  double worst = 0;
  if (result)
    for (int i = 0; i < stations; ++i) worst = std::max(worst, (result->world_from_scan[i].translation() - truth[i].translation()).norm());
  table.Add({kSection, "adjustment " + std::to_string(stations) + " stations, " + std::to_string(n_targets) + " targets", t, "s",
             std::to_string(observations.size()) + " observations, " + std::to_string(control.size()) +
                 " control (leave-one-out blunder test included); worst scan " +
                 (result ? std::to_string(worst * 1000).substr(0, 4) + " mm" : result.error().message)});
}

// Walls with a 20 cm checkerboard 2 mm proud of each, at `ranges`, turned 30° from the line of sight.
Scene BoardYard(const std::vector<Eigen::Vector3d>& centres) {
  Scene scene;
  scene.AddRectangle(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), 80, 80,
                     scene.AddTexture(SurfaceTexture::Uniform(0.4f)));
  SurfaceTexture wall = SurfaceTexture::Uniform(0.55f);
  wall.noise_amplitude = 0.1f;
  const int wall_tex = scene.AddTexture(wall);
  SurfaceTexture pattern = SurfaceTexture::Uniform(0.9f);
  pattern.checker_half_m = 0.1;
  const int checker = scene.AddTexture(pattern);
  for (const Eigen::Vector3d& c : centres) {
    const Eigen::Vector3d n = Eigen::AngleAxisd(0.52, Eigen::Vector3d::UnitZ()) * Eigen::Vector3d(-c.x(), -c.y(), 0).normalized();
    const Eigen::Vector3d u = Eigen::Vector3d::UnitZ().cross(n).normalized(), v = n.cross(u);
    scene.AddRectangle(c - 0.002 * n, u, v, 1.5, 1.5, wall_tex);
    scene.AddRectangle(c, u, v, 0.125, 0.125, checker);
  }
  scene.Build();
  return scene;
}

void CheckerSection(Table& table, bool quick) {
  const std::vector<double> ranges = quick ? std::vector<double>{5, 15} : std::vector<double>{5, 10, 15, 20, 25, 30};
  std::vector<Eigen::Vector3d> boards;
  for (std::size_t k = 0; k < ranges.size(); ++k) {
    const double a = 0.9 * k + 0.3;
    boards.emplace_back(ranges[k] * std::cos(a), ranges[k] * std::sin(a), 1.8);
  }
  const Scene scene = BoardYard(boards);
  CancelToken cancel;
  for (const auto& [cols, rows, el_min, el_max, label] :
       {std::tuple{3000, 750, -40.0, 50.0, "0.12°"}, std::tuple{6000, 667, -20.0, 20.0, "0.06°"}}) {
    const Scan scan = ScanOf(scene, cols, rows, el_min, el_max);
    std::vector<Eigen::Vector3d> found;
    const double t = Seconds([&] {
      for (const georef::DetectedChecker& d : georef::DetectCheckerTargets(scan, {}, cancel).value())
        found.push_back(d.center);
    });
    int right = 0;
    for (const Eigen::Vector3d& b : boards) right += ErrorMm(found, b - Eigen::Vector3d(0, 0, 1.6)) >= 0;
    table.Add({kSection, std::string("checkerboards found per scan, ") + label, t, "s",
               std::to_string(cols) + "x" + std::to_string(rows) + ", 2 mm noise: " + std::to_string(right) + " of " +
                   std::to_string(boards.size()) + " right, " + std::to_string(found.size() - right) + " false"});
    for (std::size_t k = 0; k < ranges.size(); ++k) {
      const double e = ErrorMm(found, boards[k] - Eigen::Vector3d(0, 0, 1.6));
      table.Add({kSection, "checkerboard centre error at " + std::to_string(int(ranges[k])) + " m, " + label, e, "mm",
                 e < 0 ? "not found (too few cells across the pattern, or its sigma > 3 mm)" : "20 cm board, 30° incidence"});
    }
  }
}

}  // namespace

void RunGeorefBench(Table& table, bool quick) {
  DetectionSection(table);
  AccuracySection(table, quick);
  CheckerSection(table, quick);
  AdjustmentSection(table, quick);
}

}  // namespace scanreg::bench
