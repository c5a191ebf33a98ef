// Registration section (issue 3, "Benchmark"): W's pipeline at the paper's size — time per stage,
// peak memory, the accuracy table against the simulator's truth, the method alternatives (coarse
// EPnP / 3D, fine keypoints / dense) and PCL's own FPFH + SampleConsensusPrerejective + ICP on the
// same tree pairs as the baseline.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <unistd.h>
#include <vector>

#include "core/features/feature_cache.h"
#include "core/features/sift.h"
#include "core/geometry/transform.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/pcl_baseline.h"

namespace scanreg::bench {
namespace {

constexpr double kDeg = 180.0 / M_PI;
const char* kSection = "register";

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double Max(const std::vector<double>& v) { return v.empty() ? NAN : *std::max_element(v.begin(), v.end()); }

int IndexOf(const std::vector<Scan>& scans, const std::string& name) {
  for (std::size_t i = 0; i < scans.size(); ++i)
    if (scans[i].name == name) return static_cast<int>(i);
  return -1;
}

Eigen::Isometry3d TrueParentFromChild(const Scan& parent, const Scan& child) {
  return parent.reference_world_from_scan->inverse() * *child.reference_world_from_scan;
}

// Tree links of a result (chained, not loop checks, not failed).
std::vector<const io::LinkRecord*> TreeLinks(const pipeline::ProjectRegistration& r) {
  std::vector<const io::LinkRecord*> out;
  for (const io::LinkRecord& l : r.links)
    if (!l.loop_check && l.status != io::LinkStatus::kFailed) out.push_back(&l);
  return out;
}

Expected<pipeline::ProjectRegistration> Run(const std::vector<Scan>& scans, const pipeline::RegisterOptions& options) {
  NullProgress progress;
  CancelToken cancel;
  return pipeline::RegisterScans(scans, {}, options, progress,
                                 cancel);
}

// Summary of a registration against the truth: non-root scans registered, their position errors.
struct Accuracy {
  int registered = 0;  // including the root
  std::vector<double> coarse_mm, fine_mm, coarse_deg, fine_deg;
  std::vector<double> pair_seconds;  // tree links
};

Accuracy Summarize(const pipeline::ProjectRegistration& r, const std::vector<Scan>& scans) {
  Accuracy a;
  const std::vector<pipeline::ReferenceError> errors = pipeline::ReferenceErrors(r, scans);
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (!r.scans[i].registered) continue;
    ++a.registered;
    if (static_cast<int>(i) == r.root || !errors[i].available) continue;
    a.fine_mm.push_back(1000 * errors[i].position_m);
    a.fine_deg.push_back(kDeg * errors[i].angle_rad);
    if (errors[i].has_coarse) {
      a.coarse_mm.push_back(1000 * errors[i].coarse_position_m);
      a.coarse_deg.push_back(kDeg * errors[i].coarse_angle_rad);
    }
  }
  for (const io::LinkRecord* l : TreeLinks(r)) a.pair_seconds.push_back(l->seconds);
  return a;
}

void AddCombinationRows(Table& table, const std::string& label, const Expected<pipeline::ProjectRegistration>& r,
                        const std::vector<Scan>& scans) {
  if (!r) {
    table.Add({kSection, label + ": registration", 0.0, "", "failed: " + r.error().ToString()});
    return;
  }
  const Accuracy a = Summarize(*r, scans);
  const int n = static_cast<int>(scans.size());
  table.Add({kSection, label + ": registered scans", static_cast<double>(a.registered), "scans",
             "of " + std::to_string(n) + "; loop checks off"});
  table.Add({kSection, label + ": position error after fine, median", Median(a.fine_mm), "mm",
             Fmt("max %.1f mm; after coarse median %.1f / max %.1f mm", Max(a.fine_mm), Median(a.coarse_mm),
                 Max(a.coarse_mm))});
  table.Add({kSection, label + ": angle error after fine, max", Max(a.fine_deg), "deg",
             Fmt("after coarse max %.3f deg", Max(a.coarse_deg))});
  table.Add({kSection, label + ": coarse + fine per tree pair, median", Median(a.pair_seconds), "s",
             Fmt("max %.2f s; end to end %.1f s (features from cache)", Max(a.pair_seconds), r->seconds_total)});
}

}  // namespace

void RunRegisterBench(Table& table, bool quick) {
  SimulatedProjectOptions sim;
  sim.seed = 1;
  sim.scanner.seed = 1;
  sim.scanner.range_noise_m = 0.012;
  if (quick) {
    sim.stations = 4;
    sim.scanner.cols = 1000;
    sim.scanner.rows = 250;
  } else {
    sim.stations = 11;
    sim.scanner.cols = 3000;
    sim.scanner.rows = 750;
  }
  const std::string size = std::to_string(sim.stations) + " stations " + std::to_string(sim.scanner.cols) + "x" +
                           std::to_string(sim.scanner.rows);
  Expected<std::vector<Scan>> simulated = MakeError(ErrorCode::kFailed, "not run");
  const double sim_s = Seconds([&] {
    NullProgress progress;
    CancelToken cancel;
    simulated = SimulateProject(sim, progress, cancel);
  });
  if (!simulated) {
    table.Add({kSection, "simulate " + size, 0.0, "", "failed: " + simulated.error().ToString()});
    return;
  }
  const std::vector<Scan>& scans = *simulated;
  const int n = static_cast<int>(scans.size());
  table.Add({kSection, "simulate project (" + size + ")", sim_s, "s",
             "sigma 12 mm, seed 1, 5 m spacing; setup, not part of the registration"});

  // --- Stage times. SIFT per scan on its own (this also fills a feature cache that the method
  // comparison below reuses); the default run itself does not use the cache.
  const std::filesystem::path cache_dir =
      std::filesystem::temp_directory_path() / ("scanreg-bench-features-" + std::to_string(::getpid()));
  std::vector<double> sift_s;
  std::vector<double> feature_counts;
  pipeline::RegisterOptions defaults;
  for (const Scan& s : scans) {
    Expected<ScanFeatures> f = MakeError(ErrorCode::kFailed, "not run");
    sift_s.push_back(Seconds([&] { f = LoadOrDetectFeatures(s, defaults.sift, cache_dir); }));
    if (f) feature_counts.push_back(f->size());
  }
  std::printf("[register] SIFT done (%d scans), running the default registration ...\n", n);
  std::fflush(stdout);

  Expected<pipeline::ProjectRegistration> def = Run(scans, defaults);
  const double peak_after_default = PeakMemoryMiB();
  table.Add({kSection, "SIFT per scan, median", Median(sift_s), "s",
             Fmt("max %.2f s; median %.0f features/scan; W: part of 5 s per pair", Max(sift_s), Median(feature_counts))});
  if (!def) {
    table.Add({kSection, "default registration", 0.0, "", "failed: " + def.error().ToString()});
    std::filesystem::remove_all(cache_dir);
    return;
  }
  const Accuracy acc = Summarize(*def, scans);
  const std::vector<const io::LinkRecord*> tree = TreeLinks(*def);
  double all_links_s = 0;
  int attempts = 0;
  for (const io::LinkRecord& l : def->links) all_links_s += l.seconds, ++attempts;
  table.Add({kSection, "confusion matrix, all " + std::to_string(n * (n - 1)) + " ordered pairs", def->seconds_matching,
             "s", "exact ratio matching t_des 0.66, both directions per product"});
  table.Add({kSection, "coarse + fine per tree pair, median", Median(acc.pair_seconds), "s",
             Fmt("%.0f tree pairs, max %.2f s; goal <= 1 s; W: 8 s (7 s EPnP-RANSAC + 1 s ICP)",
                 static_cast<double>(tree.size()), Max(acc.pair_seconds))});
  table.Add({kSection, "coarse + fine per tree pair, max", Max(acc.pair_seconds), "s", "3d + dense"});
  table.Add({kSection, "all pair registrations (tree + loop checks)", def->seconds_pairs, "s",
             Fmt("%.0f link records kept, sum of their times %.1f s", static_cast<double>(attempts), all_links_s)});
  table.Add({kSection, "end to end (RegisterScans)", def->seconds_total, "s",
             Fmt("goal <= 60 s; features %.1f s, matching %.1f s, pairs %.1f s", def->seconds_features,
                 def->seconds_matching, def->seconds_pairs)});
  table.Add({kSection, "peak resident memory after the default run", peak_after_default, "MiB",
             "process VmHWM incl. simulated scans"});

  // --- Accuracy of the default options: per-scan table, then summary rows.
  const std::vector<pipeline::ReferenceError> errors = pipeline::ReferenceErrors(*def, scans);
  std::printf("\n[register] default options (coarse 3d + fine dense, loop checks on), %s, root %s\n", size.c_str(),
              def->root >= 0 ? scans[def->root].name.c_str() : "-");
  std::printf("%-5s %-6s %-7s %9s %9s %9s %9s  %7s %8s %7s %10s %8s\n", "scan", "parent", "status", "coarse mm",
              "coarse deg", "fine mm", "fine deg", "matches", "reliable", "inliers", "consistent", "pair s");
  for (int i = 0; i < n; ++i) {
    const pipeline::ScanRegistration& s = def->scans[i];
    const io::LinkRecord* link = nullptr;
    for (const io::LinkRecord* l : tree)
      if (l->child == scans[i].name) link = l;
    if (!s.registered) {
      std::printf("%-5s %-6s %-7s %s\n", scans[i].name.c_str(), "-", "not reg", s.reason.c_str());
      continue;
    }
    if (i == def->root) {
      std::printf("%-5s %-6s %-7s %9s\n", scans[i].name.c_str(), "-", "root", "-");
      continue;
    }
    const pipeline::ReferenceError& e = errors[i];
    std::printf("%-5s %-6s %-7s %9.1f %9.4f %9.1f %9.4f  %7d %8d %7d %10d %8.2f\n", scans[i].name.c_str(),
                scans[s.parent].name.c_str(), link ? io::LinkStatusName(link->status) : "?",
                e.has_coarse ? 1000 * e.coarse_position_m : NAN, e.has_coarse ? kDeg * e.coarse_angle_rad : NAN,
                1000 * e.position_m, kDeg * e.angle_rad, link ? link->matches : 0, link ? link->reliable : 0,
                link ? link->ransac_inliers : 0, link ? link->consistent : 0, link ? link->seconds : 0.0);
  }
  std::fflush(stdout);
  table.Add({kSection, "default (3d+dense): registered scans", static_cast<double>(acc.registered), "scans",
             "of " + std::to_string(n) + ", loop checks on"});
  table.Add({kSection, "default: position error after coarse, median", Median(acc.coarse_mm), "mm",
             Fmt("max %.1f mm over %.0f scans with an unambiguous coarse chain; W: 12-49 mm after coarse",
                 Max(acc.coarse_mm), static_cast<double>(acc.coarse_mm.size()))});
  table.Add({kSection, "default: position error after coarse, max", Max(acc.coarse_mm), "mm", "W: 49 mm"});
  table.Add({kSection, "default: position error after fine, median", Median(acc.fine_mm), "mm",
             Fmt("max %.1f mm; W: 9-32 mm after fine", Max(acc.fine_mm))});
  table.Add({kSection, "default: position error after fine, max", Max(acc.fine_mm), "mm", "W: 32 mm"});
  table.Add({kSection, "default: angle error after coarse, median / max", Median(acc.coarse_deg), "deg",
             Fmt("max %.4f deg", Max(acc.coarse_deg))});
  table.Add({kSection, "default: angle error after fine, median / max", Median(acc.fine_deg), "deg",
             Fmt("max %.4f deg", Max(acc.fine_deg))});

  // --- The four method combinations, loop checks off, SIFT from the cache.
  std::printf("[register] method combinations ...\n");
  std::fflush(stdout);
  for (CoarseMethod coarse : {CoarseMethod::kEpnp, CoarseMethod::k3d}) {
    for (pipeline::FineMethod fine : {pipeline::FineMethod::kKeypoints, pipeline::FineMethod::kDense}) {
      pipeline::RegisterOptions o;
      o.coarse.method = coarse;
      o.fine = fine;
      o.verify_loops = false;
      o.feature_cache_dir = cache_dir;
      const std::string label =
          std::string(pipeline::CoarseMethodName(coarse)) + "+" + pipeline::FineMethodName(fine);
      AddCombinationRows(table, label, Run(scans, o), scans);
    }
  }
  std::filesystem::remove_all(cache_dir);

  // --- PCL baseline on the default run's tree pairs.
  std::printf("[register] PCL baseline on %zu tree pairs ...\n", tree.size());
  std::fflush(stdout);
  const PclOptions pcl_options;
  std::vector<double> pcl_total, pcl_features, pcl_align, pcl_mm, pcl_ok_mm;
  int pcl_success = 0;
  for (const io::LinkRecord* l : tree) {
    const int p = IndexOf(scans, l->parent), c = IndexOf(scans, l->child);
    if (p < 0 || c < 0) continue;
    const PclPairResult r = PclRegisterPair(scans[p], scans[c], pcl_options);
    const PoseError e = ComparePoses(r.parent_from_child, TrueParentFromChild(scans[p], scans[c]));
    const bool ok = e.position_m < 0.1 && e.angle_rad * kDeg < 1.0;
    pcl_success += ok;
    pcl_total.push_back(r.seconds_features + r.seconds_sac + r.seconds_icp);
    pcl_features.push_back(r.seconds_features);
    pcl_align.push_back(r.seconds_sac + r.seconds_icp);
    pcl_mm.push_back(1000 * e.position_m);
    if (ok) pcl_ok_mm.push_back(1000 * e.position_m);
    std::printf("[register] PCL %s->%s: %.2f s (features %.2f, SAC %.2f, ICP %.2f), child/parent %zu/%zu pts "
                "(coarse %zu/%zu), sac %s, error %.1f mm %.3f deg%s\n",
                l->child.c_str(), l->parent.c_str(), r.seconds_features + r.seconds_sac + r.seconds_icp,
                r.seconds_features, r.seconds_sac, r.seconds_icp, r.child_points, r.parent_points,
                r.child_coarse_points, r.parent_coarse_points, r.converged ? "converged" : "not converged",
                1000 * e.position_m, e.angle_rad * kDeg, ok ? "" : "  FAIL");
    std::fflush(stdout);
  }
  const std::string params =
      Fmt("voxel %.2f m for FPFH/SAC (normals r %.2f m, FPFH r %.2f m), ", pcl_options.coarse_voxel_m,
          pcl_options.normal_radius_m, pcl_options.fpfh_radius_m) +
      Fmt("%.2f m for ICP, range <= %.0f m", pcl_options.fine_voxel_m, pcl_options.max_range_m);
  const std::string sac_params =
      Fmt("SAC-prerejective %.0f it, 3 samples, k 5, sim 0.9, d %.2f m, inlier fraction 0.25; ",
          pcl_options.max_iterations, pcl_options.sac_max_distance_m) +
      Fmt("ICP d %.2f m, 50 it", pcl_options.icp_max_distance_m);
  table.Add({kSection, "PCL FPFH+SAC-prerej+ICP: time per pair, median", Median(pcl_total), "s",
             Fmt("max %.1f s; features %.1f s + align %.1f s (medians); ", Max(pcl_total), Median(pcl_features),
                 Median(pcl_align)) +
                 params});
  table.Add({kSection, "PCL FPFH+SAC-prerej+ICP: successful pairs", static_cast<double>(pcl_success), "pairs",
             "of " + std::to_string(pcl_total.size()) + " tree pairs; success: < 0.1 m and < 1 deg; " + sac_params});
  table.Add({kSection, "PCL FPFH+SAC-prerej+ICP: position error, median", Median(pcl_mm), "mm",
             Fmt("all pairs (relative pose); max %.0f mm; median of successes %.1f mm", Max(pcl_mm),
                 Median(pcl_ok_mm))});
}

}  // namespace scanreg::bench
