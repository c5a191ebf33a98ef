// City section (issue 13, "Benchmark"): a campaign on the simulated city — streets that close
// loops — registered end to end with candidate pairs: time per stage, peak memory, how many pairs
// were matched, the share of the truly overlapping pairs (>= 30 % at the true poses) considered
// (matched, or refined from the registered poses for the global step), and the
// position errors (the worst is the drift round the loops) with and without the global step.
// Quick: 28 stations at 1000 x 250 (the ring round one block, closed), also matched exhaustively
// for the matching time beside it. Last, the scans written to disk (binary scan-cache files, as a
// reopened project reads them) and dropped from memory, then registered through a scan store
// under a memory budget of a fifth of the scans (issue 13, item 1): the peak memory of that run
// alone, and its result against the in-memory one. The full size (100 stations at 3000 x 750) runs
// from disk only: its scans alone would take 3.8 GB.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/io/scan_cache.h"
#include "core/io/text_parse.h"
#include "core/pipeline/candidate_pairs.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/scan_store.h"
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

// scans: their names and reference poses (heads will do).
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

// Scans written as binary scan-cache files (as a reopened project reads them) to a temporary folder,
// removed with this object; Read gives one back at a time, for a ScanStore.
struct DiskScans {
  std::filesystem::path dir;
  std::vector<std::filesystem::path> files;
  std::vector<Scan> heads;  // names, poses and reference poses
  std::size_t all_bytes = 0;

  DiskScans(const std::vector<Scan>& scans, const std::string& tag) {
    namespace fs = std::filesystem;
    dir = fs::temp_directory_path() / ("scanreg-bench-" + tag + "-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    for (std::size_t i = 0; i < scans.size(); ++i) {
      files.push_back(dir / ("scan" + std::to_string(i) + ".scan"));
      std::ofstream(files.back(), std::ios::binary) << io::SerializeScanCache({scans[i]}, i);
      heads.push_back(pipeline::ScanHead(scans[i]));
      all_bytes += pipeline::ScanBytes(scans[i]);
    }
  }
  ~DiskScans() { std::filesystem::remove_all(dir); }
  pipeline::ScanStore::Reader Read() const {
    return [files = files](int i) -> Expected<Scan> {
      Expected<std::string> bytes = io::ReadWholeFile(files[i]);
      if (!bytes) return bytes.error();
      Expected<std::vector<Scan>> parsed = io::ParseScanCache(*bytes, i);
      if (!parsed) return parsed.error();
      return std::move(parsed->front());
    };
  }
};

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

  const DiskScans disk(*scans, "city");  // for the runs through a store
  const std::vector<Scan>& heads = disk.heads;
  std::vector<Eigen::Isometry3d> in_memory_poses;
  auto run = [&](int candidates, bool global, const std::string& label, pipeline::ScanStore* store) {
    pipeline::RegisterOptions options;
    options.candidates = candidates;
    options.global = global;
    if (store) ResetPeakMemory();
    auto r = store ? pipeline::RegisterScans(*store, {}, options, progress, CancelToken())
                   : pipeline::RegisterScans(*scans, {}, options, progress, CancelToken());
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
    const Errors e = Measure(*r, heads);
    char note[240];
    std::snprintf(note, sizeof note, "features %.0f s, matching %.0f s, pairs %.0f s; peak RSS %s %.0f MiB",
                  r->seconds_features, r->seconds_matching, r->seconds_pairs, store ? "of this run" : "so far",
                  PeakMemoryMiB());
    table.Add({kSection, label + ": register end to end", r->seconds_total, "s", note});
    if (store) {
      double moved = 0;  // against the same run in memory
      for (int i = 0; i < n && !in_memory_poses.empty(); ++i)
        moved = std::max(moved, (r->scans[i].world_from_scan.translation() - in_memory_poses[i].translation()).norm());
      char same[80] = "no in-memory run to compare";
      if (!in_memory_poses.empty()) std::snprintf(same, sizeof same, "poses within %.2g mm of the in-memory run", moved * 1e3);
      std::snprintf(note, sizeof note, "%d reads of %d scans, %d surface builds, at most %s held (budget %s); %s",
                    store->reads(), n, store->surface_builds(), FormatBytes(store->peak_bytes()).c_str(),
                    FormatBytes(store->budget_bytes()).c_str(), same);
      table.Add({kSection, label + ": peak resident memory", PeakMemoryMiB(), "MiB", note});
    } else if (candidates == 10 && global) {
      for (const auto& s : r->scans) in_memory_poses.push_back(s.world_from_scan);
    }
    std::snprintf(note, sizeof note, "%d of %d pairs matched (%.1f %% of the %zu overlapping >= 30 %%), %zu refined",
                  r->pairs_matched, r->pairs_possible, 100.0 * pipeline::PairRecall(overlapping, matched),
                  overlapping.size(), r->pairs_by_overlap.size());
    table.Add({kSection, label + ": overlapping pairs considered", 100.0 * pipeline::PairRecall(overlapping, considered),
               "%", note});
    std::snprintf(note, sizeof note, "%d of %d registered; median %.1f mm", e.registered, n, e.median_m * 1000);
    table.Add({kSection, label + ": worst position error (drift)", e.worst_m * 1000, "mm", note});
  };
  if (quick) {
    run(10, true, "candidates 10, global", nullptr);
    run(10, false, "candidates 10, tree only", nullptr);
    run(0, true, "every pair, global", nullptr);
  }
  scans->clear();
  scans->shrink_to_fit();
  pipeline::ScanStore store(heads, disk.Read(), disk.all_bytes / 5);
  run(10, true, "from disk, budget 1/5 of the scans, candidates 10, global", &store);
  if (!quick) {
    pipeline::ScanStore again(heads, disk.Read(), disk.all_bytes / 5);
    run(10, false, "from disk, budget 1/5 of the scans, candidates 10, tree only", &again);
  }
}

// Scans of 10 M points (issue 13, "Benchmark": 10 stations at 10 M points each): a street of 10
// stations at 5000 x 2000, written to disk and registered through a store under a 1 GiB budget with
// the default options, as `scanreg-cli register --memory-budget 1G` runs it (feature cache aside).
// Quick: 3 stations at 2000 x 1000 under 256 MiB.
void RunBigScansBench(Table& table, bool quick) {
  constexpr const char* kBig = "big scans";
  SimulatedProjectOptions o;
  o.stations = quick ? 3 : 10;
  o.scanner.cols = quick ? 2000 : 5000;
  o.scanner.rows = quick ? 1000 : 2000;
  const std::size_t budget = quick ? std::size_t(256) << 20 : std::size_t(1) << 30;
  const std::string size = std::to_string(o.stations) + " x " + std::to_string(o.scanner.cols) + "x" +
                           std::to_string(o.scanner.rows) + " (" +
                           Fmt("%.0f", o.scanner.cols * double(o.scanner.rows) / 1e6) + " M points each)";
  NullProgress progress;
  Expected<std::vector<Scan>> scans = MakeError(ErrorCode::kFailed, "not simulated");
  const double sim_s = Seconds([&] { scans = SimulateProject(o, progress, CancelToken()); });
  if (!scans) {
    table.Add({kBig, "simulate " + size, 0.0, "", "failed: " + scans.error().ToString()});
    return;
  }
  table.Add({kBig, "simulate " + size, sim_s, "s", "the street scene"});
  const DiskScans disk(*scans, "big");
  scans = MakeError(ErrorCode::kFailed, "dropped: read from disk");
  pipeline::ScanStore store(disk.heads, disk.Read(), budget);
  ResetPeakMemory();
  auto r = pipeline::RegisterScans(store, {}, pipeline::RegisterOptions(), progress, CancelToken());
  if (!r) {
    table.Add({kBig, size + ": register", 0.0, "", "failed: " + r.error().ToString()});
    return;
  }
  const Errors e = Measure(*r, disk.heads);
  const int n = int(disk.heads.size());
  table.Add({kBig, size + ": register end to end", r->seconds_total, "s",
             Fmt("features %.0f s, matching %.0f s, pairs %.0f s", r->seconds_features, r->seconds_matching,
                 r->seconds_pairs)});
  table.Add({kBig, size + ": peak resident memory", PeakMemoryMiB(), "MiB",
             std::to_string(store.reads()) + " reads of " + std::to_string(n) + " scans, " +
                 std::to_string(store.surface_builds()) + " surface builds, at most " +
                 FormatBytes(store.peak_bytes()) + " held (budget " +
                 FormatBytes(store.budget_bytes()) + "); the scans take " +
                 FormatBytes(disk.all_bytes)});
  table.Add({kBig, size + ": worst position error", e.worst_m * 1000, "mm",
             Fmt("%.0f of %.0f registered; median %.1f mm", e.registered, n, e.median_m * 1000)});
}

}  // namespace scanreg::bench
