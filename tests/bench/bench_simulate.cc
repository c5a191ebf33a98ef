// Simulator section: rays per second for one panoramic scan of the street scene.
#include <string>

#include "core/simulate/scanner.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {

void RunSimulateBench(Table& table, bool quick) {
  ScannerOptions options;
  if (quick) {
    options.cols = 750;
    options.rows = 188;
  }
  Scene scene;
  const double build_s = Seconds([&] { scene = MakeScene(SceneOptions()); });
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(1.0, 0.5, 1.7);
  NullProgress progress;
  CancelToken cancel;
  Expected<Scan> scan = MakeError(ErrorCode::kFailed, "not run");
  const double s = Seconds([&] { scan = SimulateScan(scene, pose, options, "bench", progress, cancel); });
  const std::string size = std::to_string(options.cols) + " x " + std::to_string(options.rows);
  if (!scan) {
    table.Add({"simulate", "simulate " + size + " scan", 0.0, "", "failed: " + scan.error().ToString()});
    return;
  }
  const double rays = static_cast<double>(options.cols) * options.rows;
  table.Add({"simulate", "build street scene", build_s * 1e3, "ms",
             std::to_string(scene.num_primitives()) + " primitives"});
  table.Add({"simulate", "simulate " + size + " scan", rays / s / 1e6, "M rays/s",
             std::to_string(s).substr(0, 5) + " s wall, OpenMP over rows"});
  table.Add({"simulate", "valid-point fraction", static_cast<double>(scan->CountValid()) / scan->size(), "",
             "street station, max range " + std::to_string(static_cast<int>(options.max_range_m)) + " m"});
}

}  // namespace scanreg::bench
