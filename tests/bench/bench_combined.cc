// Hard conditions together (issue 37, "Benchmark"): busy streets (12 m spacing, 6 vehicles and 12
// pedestrians placed anew in every scan, angle noise, range noise growing with range), the same with
// stations tilted up to 5°, and a static street 25 m apart, 1000x250, through scanreg's whole
// pipeline — with the default options (FPFH at the fine scale) and with --coarse-scale 3 — and
// every neighbouring pair through the baseline: FPFH at a 0.5 m voxel + mutual filter +
// RANSAC (100 k) + point-to-plane ICP, as Open3D's tutorial sets it (fpfh_ransac_baseline.h). Right: within 2 cm / 0.1° of the truth
// (scans), 5 cm / 0.2° (pairs).
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/geometry/transform.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/fpfh_ransac_baseline.h"

namespace scanreg::bench {
namespace {

constexpr const char* kSection = "combined";
constexpr double kDeg = 180.0 / M_PI;

struct Combined {
  std::string name;
  int stations;
  double spacing_m;
  int traffic;     // vehicles; twice as many pedestrians
  double tilt_deg;
  std::uint64_t seed;
  bool baseline;   // also through the FPFH + RANSAC baseline
};

void RunScanreg(Table& table, const std::string& label, const std::vector<Scan>& scans,
                const pipeline::RegisterOptions& options) {
  NullProgress progress;
  CancelToken cancel;
  Expected<pipeline::ProjectRegistration> r = MakeError(ErrorCode::kFailed, "not run");
  const double seconds = Seconds([&] { r = pipeline::RegisterScans(scans, {}, options, progress, cancel); });
  if (!r) {
    table.Add({kSection, label, 0.0, "", "failed: " + r.error().ToString()});
    return;
  }
  const std::vector<pipeline::ReferenceError> errors = pipeline::ReferenceErrors(*r, scans);
  const int n = static_cast<int>(scans.size());
  int registered = 0, wrong = 0;
  for (int i = 0; i < n; ++i) {
    if (!r->scans[i].registered) continue;
    ++registered;
    wrong += !(errors[i].position_m <= 0.02 && errors[i].angle_rad * kDeg <= 0.1);
  }
  char note[160];
  std::snprintf(note, sizeof note, "%d of %d registered (root included), %d of them wrong; %.1f s", registered, n,
                wrong, seconds);
  table.Add({kSection, label + " scans right", static_cast<double>(registered - wrong), "scans", note});
}

}  // namespace

void RunCombinedBench(Table& table, bool quick) {
  std::vector<Combined> projects = {
      {"busy 12 m", 6, 12.0, 6, 0.5, 3, true},         {"busy 12 m", 6, 12.0, 6, 0.5, 5, false},
      {"busy 12 m", 6, 12.0, 6, 0.5, 7, false},        {"busy 12 m tilted 5°", 6, 12.0, 6, 5.0, 3, true},
      {"busy 12 m tilted 5°", 6, 12.0, 6, 5.0, 5, false}, {"busy 12 m tilted 5°", 6, 12.0, 6, 5.0, 7, false},
      {"static 25 m", 5, 25.0, 0, 0.5, 3, true},       {"static 25 m", 5, 25.0, 0, 0.5, 5, false},
  };
  if (quick) projects.resize(1);
  for (const Combined& c : projects) {
    SimulatedProjectOptions o;
    o.stations = c.stations;
    o.spacing_m = c.spacing_m;
    o.scanner.cols = 1000;
    o.scanner.rows = 250;
    o.max_tilt_deg = c.tilt_deg;
    if (c.traffic > 0) {
      o.traffic.vehicles = c.traffic;
      o.traffic.pedestrians = 2 * c.traffic;
      o.scanner.angle_noise_deg = 0.005;
      o.scanner.range_noise_per_m = 1e-4;
    }
    o.seed = o.scanner.seed = o.scene.seed = c.seed;
    NullProgress progress;
    CancelToken cancel;
    Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
    const std::string name = c.name + " (seed " + std::to_string(c.seed) + ")";
    if (!scans) {
      table.Add({kSection, name + ": simulate", 0.0, "", "failed: " + scans.error().ToString()});
      continue;
    }
    RunScanreg(table, name + ": scanreg default (fine FPFH)", *scans, pipeline::RegisterOptions{});
    pipeline::RegisterOptions coarse;
    coarse.geometric.coarse_scale = 3.0;
    RunScanreg(table, name + ": scanreg --coarse-scale 3", *scans, coarse);
    if (!c.baseline || quick) continue;
    int right = 0, accepted_wrong = 0, pairs = 0;
    double baseline_seconds = 0;
    for (std::size_t i = 0; i + 1 < scans->size(); ++i) {
      const Scan& parent = (*scans)[i];
      const Scan& child = (*scans)[i + 1];
      const FpfhRansacResult a = FpfhRansacPair(parent, child, FpfhRansacOptions{});  // 0.5 m voxel, 100k it
      const PoseError e =
          ComparePoses(a.parent_from_child, parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan);
      const bool ok = e.position_m <= 0.05 && e.angle_rad * kDeg <= 0.2;
      ++pairs;
      right += a.accepted && ok;
      accepted_wrong += a.accepted && !ok;
      baseline_seconds += a.Seconds();
    }
    char note[160];
    std::snprintf(note, sizeof note, "%d of %d neighbouring pairs right, %d wrong accepts, %.1f s per pair", right,
                  pairs, accepted_wrong, pairs ? baseline_seconds / pairs : 0.0);
    table.Add({kSection, name + ": FPFH+mutual+RANSAC+ICP pairs right", static_cast<double>(right), "pairs", note});
  }
}

}  // namespace scanreg::bench
