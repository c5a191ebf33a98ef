// City section (issue 13, "Benchmark"): a campaign on the simulated city — streets that close
// loops — registered end to end with candidate pairs: time per stage, peak memory, how many pairs
// were matched, the share of the truly overlapping pairs (>= 30 % at the true poses) considered
// (matched, or refined from the registered poses for the global step), and the
// position errors (the worst is the drift round the loops) with and without the global step.
// Quick: 28 stations at 1000 x 250 (the ring round one block, closed), also matched exhaustively
// for the matching time beside it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "core/pipeline/candidate_pairs.h"
#include "core/pipeline/register_project.h"
#include "core/registration/voxel_filter.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {
namespace {

constexpr const char* kSection = "city";

struct Errors {
  int registered = 0;
  double median_m = NAN, worst_m = NAN;
};

Errors Measure(const pipeline::ProjectRegistration& r, const std::vector<Scan>& scans) {
  Errors e;
  std::vector<double> d;
  const auto errors = pipeline::ReferenceErrors(r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!r.scans[i].registered || !errors[i].available) continue;
    ++e.registered;
    d.push_back(errors[i].position_m);
  }
  if (d.empty()) return e;
  std::sort(d.begin(), d.end());
  e.median_m = d[d.size() / 2];
  e.worst_m = d.back();
  return e;
}

}  // namespace

void RunCityBench(Table& table, bool quick) {
  SimulatedProjectOptions o;
  o.scene.kind = SceneOptions::Kind::kCity;
  o.stations = quick ? 28 : 100;
  o.spacing_m = 10.0;
  o.scanner.cols = quick ? 1000 : 3000;
  o.scanner.rows = quick ? 250 : 750;
  const std::string size = std::to_string(o.stations) + " stations " + std::to_string(o.scanner.cols) + "x" +
                           std::to_string(o.scanner.rows) + ", 10 m";
  NullProgress progress;
  Expected<std::vector<Scan>> scans = MakeError(ErrorCode::kFailed, "not simulated");
  const double sim_s = Seconds([&] { scans = SimulateProject(o, progress, CancelToken()); });
  if (!scans) {
    std::fprintf(stderr, "city: %s\n", scans.error().message.c_str());
    return;
  }
  table.Add({kSection, "simulate " + size, sim_s, "s", "the city grows to hold the stations"});

  std::vector<std::vector<Eigen::Vector3d>> samples;
  std::vector<Eigen::Isometry3d> truth;
  for (const Scan& s : *scans) {
    samples.push_back(VoxelDownsample(ValidPoints(s), 0.2));
    truth.push_back(*s.reference_world_from_scan);
  }
  const auto overlapping = pipeline::OverlappingPairs(samples, truth, 0.3, 0.3);
  samples.clear();
  const int n = static_cast<int>(scans->size());

  auto run = [&](int candidates, bool global, const std::string& label) {
    pipeline::RegisterOptions options;
    options.candidates = candidates;
    options.global = global;
    auto r = pipeline::RegisterScans(*scans, {}, options, progress, CancelToken());
    if (!r) {
      std::fprintf(stderr, "city: %s\n", r.error().message.c_str());
      return;
    }
    std::vector<std::pair<int, int>> matched;
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j)
        if (r->confusion(i, j) != kSkippedPair) matched.emplace_back(i, j);
    std::vector<std::pair<int, int>> considered = matched;  // matched, or refined at the registered poses
    for (const auto& [p, c] : r->pairs_by_overlap) considered.emplace_back(std::min(p, c), std::max(p, c));
    const Errors e = Measure(*r, *scans);
    char note[200];
    std::snprintf(note, sizeof note, "features %.0f s, matching %.0f s, pairs %.0f s; peak RSS so far %.0f MiB",
                  r->seconds_features, r->seconds_matching, r->seconds_pairs, PeakMemoryMiB());
    table.Add({kSection, label + ": register end to end", r->seconds_total, "s", note});
    std::snprintf(note, sizeof note, "%d of %d pairs matched (%.1f %% of the %zu overlapping >= 30 %%), %zu refined",
                  r->pairs_matched, r->pairs_possible, 100.0 * pipeline::PairRecall(overlapping, matched),
                  overlapping.size(), r->pairs_by_overlap.size());
    table.Add({kSection, label + ": overlapping pairs considered", 100.0 * pipeline::PairRecall(overlapping, considered),
               "%", note});
    std::snprintf(note, sizeof note, "%d of %d registered; median %.1f mm", e.registered, n, e.median_m * 1000);
    table.Add({kSection, label + ": worst position error (drift)", e.worst_m * 1000, "mm", note});
  };
  run(10, true, "candidates 10, global");
  run(10, false, "candidates 10, tree only");
  if (quick) run(0, true, "every pair, global");
}

}  // namespace scanreg::bench
