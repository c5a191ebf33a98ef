// Hard projects (issue 11, "Benchmark"): every pair of neighbouring stations, through
// scanreg's pair registration (InspectPair: the GUI's and pipeline's pair path, default options) and
// through PCL's FPFH + SampleConsensusPrerejective + ICP and PCL's K-4PCS + ICP, on the same scans:
// success rate (accepted and within 5 cm / 0.2° of the truth), wrong accepts (accepted but farther),
// time per pair. A PCL result is "accepted" when its global stage says it converged.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/geometry/transform.h"
#include "core/pipeline/inspect_pair.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/pcl_baseline.h"

namespace scanreg::bench {
namespace {

constexpr const char* kSection = "hard";
constexpr double kDeg = 180.0 / M_PI;

struct HardProject {
  std::string name;
  int stations, cols, rows;
  double spacing;
  bool reflectance;
  int traffic;
  std::uint64_t seed;
};

struct Tally {
  int pairs = 0, correct = 0, wrong = 0;
  std::vector<double> seconds;
  void Add(bool accepted, const PoseError& e, double s) {
    ++pairs;
    const bool right = e.position_m <= 0.05 && e.angle_rad * kDeg <= 0.2;
    correct += accepted && right;
    wrong += accepted && !right;
    seconds.push_back(s);
  }
  double MedianSeconds() const {
    std::vector<double> v = seconds;
    if (v.empty()) return NAN;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
};

void AddRows(Table& table, const std::string& project, const std::string& method, const Tally& t) {
  char note[160];
  std::snprintf(note, sizeof note, "%d of %d pairs right, %d wrong accepts, median %.2f s per pair", t.correct,
                t.pairs, t.wrong, t.MedianSeconds());
  table.Add({kSection, project + ": " + method + " pair success", t.pairs ? 100.0 * t.correct / t.pairs : 0.0, "%",
             note});
}

}  // namespace

void RunHardBench(Table& table, bool quick) {
  std::vector<HardProject> projects = {
      {"10 m 1000x250", 5, 1000, 250, 10.0, true, 0, 3},  {"15 m 1500x375", 4, 1500, 375, 15.0, true, 0, 4},
      {"traffic 1000x250", 6, 1000, 250, 5.0, true, 8, 8}, {"600x150", 4, 600, 150, 5.0, true, 0, 5},
      {"no reflectance", 4, 1000, 250, 5.0, false, 0, 6},
  };
  if (quick) projects.resize(1);
  for (const HardProject& h : projects) {
    SimulatedProjectOptions o;
    o.stations = h.stations;
    o.spacing_m = h.spacing;
    o.scanner.cols = h.cols;
    o.scanner.rows = h.rows;
    o.scanner.reflectance = h.reflectance;
    if (h.traffic > 0) {
      o.traffic.vehicles = h.traffic;
      o.traffic.pedestrians = 2 * h.traffic;
      o.scanner.angle_noise_deg = 0.005;
      o.scanner.range_noise_per_m = 1e-4;
    }
    o.seed = o.scanner.seed = o.scene.seed = h.seed;
    NullProgress progress;
    CancelToken cancel;
    Expected<std::vector<Scan>> scans = SimulateProject(o, progress, cancel);
    if (!scans) {
      table.Add({kSection, h.name + ": simulate", 0.0, "", "failed: " + scans.error().ToString()});
      continue;
    }
    Tally ours, sac, kfpcs;
    int kfpcs_timeouts = 0;
    const PclOptions pcl_options;
    pipeline::InspectOptions inspect;
    inspect.overlay = false;
    const int n = static_cast<int>(scans->size());
    // Neighbouring stations (each pair costs PCL a minute or more: the run stays within half an hour).
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n && j <= i + 1; ++j) {
        const Scan& parent = (*scans)[i];
        const Scan& child = (*scans)[j];
        const Eigen::Isometry3d truth = parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan;
        Expected<pipeline::PairInspection> r = MakeError(ErrorCode::kFailed, "not run");
        const double s = Seconds([&] { r = pipeline::InspectPair(parent, child, pipeline::RegisterOptions{}, inspect, progress, cancel); });
        if (r) {
          ours.Add(r->result.link.status != io::LinkStatus::kFailed, ComparePoses(r->result.link.parent_from_child, truth), s);
        }
        const PclPairResult a = PclRegisterPair(parent, child, pcl_options);
        sac.Add(a.converged, ComparePoses(a.parent_from_child, truth), a.seconds_features + a.seconds_sac + a.seconds_icp);
        // K-4PCS is stopped after 30 s (PCL's own limit does not hold).
        if (!quick) {
          bool timed_out = false;
          const PclPairResult k = PclKfpcsPair(parent, child, pcl_options, 30.0, &timed_out);
          kfpcs_timeouts += timed_out;
          kfpcs.Add(k.converged, ComparePoses(k.parent_from_child, truth), k.seconds_features + k.seconds_sac + k.seconds_icp);
        }
      }
    AddRows(table, h.name, "scanreg", ours);
    AddRows(table, h.name, "PCL FPFH+SAC+ICP", sac);
    if (!quick) AddRows(table, h.name, "PCL K-4PCS+ICP (" + std::to_string(kfpcs_timeouts) + " stopped at 30 s)", kfpcs);
  }
}

}  // namespace scanreg::bench
