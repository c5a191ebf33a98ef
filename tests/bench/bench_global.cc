// Global registration section (issue 4): is the pose graph (`register --global`) better than
// chaining the pairwise results along the tree? Measured with and without it on
//  (a) a simulated street registered with features (coarse 3d + fine dense),
//  (b) the same links with drift injected into one tree link (5 cm, 0.3 deg),
//  (c) the same links plus one wrong extra link (1 m, 5 deg off) - the failure case,
//  (d) the Stanford bunny, `--coarse none --fine em` from bun.conf poses perturbed by 3 deg / 3 mm.
// Errors: scan positions and angles against the reference, relative to the root.
#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include "core/geometry/transform.h"
#include "core/io/ply.h"
#include "core/io/pose_file.h"
#include "core/pipeline/global_registration.h"
#include "core/pipeline/register_project.h"
#include "core/simulate/project_sim.h"
#include "tests/bench/bench_table.h"

namespace scanreg::bench {
namespace {

constexpr double kDeg = 180.0 / M_PI;
const char* kSection = "global";

struct Worst {
  double mm = 0, deg = 0;
  int registered = 0;
};

// Worst error of the registered scans against their references, relative to the root.
Worst WorstError(const pipeline::ProjectRegistration& r, const std::vector<Scan>& scans) {
  Worst w;
  for (const pipeline::ReferenceError& e : pipeline::ReferenceErrors(r, scans)) {
    if (!e.available) continue;
    w.mm = std::max(w.mm, 1e3 * e.position_m);
    w.deg = std::max(w.deg, kDeg * e.angle_rad);
  }
  for (const pipeline::ScanRegistration& s : r.scans) w.registered += s.registered;
  return w;
}

// World poses chained from the root along the tree links (after editing a link).
void Rechain(const std::vector<Scan>& scans, pipeline::ProjectRegistration* r) {
  for (const io::LinkRecord& l : r->links) {
    if (l.loop_check || l.status == io::LinkStatus::kFailed) continue;
    int p = -1, c = -1;
    for (std::size_t i = 0; i < scans.size(); ++i) {
      if (scans[i].name == l.parent) p = static_cast<int>(i);
      if (scans[i].name == l.child) c = static_cast<int>(i);
    }
    r->scans[c].world_from_scan = r->scans[p].world_from_scan * l.parent_from_child;
  }
}

void AddPair(Table& table, const std::string& what, const Worst& tree, const Worst& global, const std::string& note) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "; angle %.4f deg (tree) vs %.4f deg (global)", tree.deg, global.deg);
  table.Add({kSection, what + ", tree only", tree.mm, "mm", note + buf});
  table.Add({kSection, what + ", --global", global.mm, "mm", std::to_string(global.registered) + " scans registered"});
}

void Street(Table& table, bool quick) {
  SimulatedProjectOptions sim;
  sim.seed = sim.scanner.seed = sim.scene.seed = 1;
  sim.scanner.range_noise_m = 0.012;
  sim.stations = quick ? 4 : 11;
  sim.scanner.cols = quick ? 1000 : 1500;
  sim.scanner.rows = quick ? 250 : 375;
  NullProgress progress;
  CancelToken cancel;
  Expected<std::vector<Scan>> scans = SimulateProject(sim, progress, cancel);
  if (!scans) {
    table.Add({kSection, "street", 0.0, "", "failed: " + scans.error().ToString()});
    return;
  }
  const std::string size = std::to_string(sim.stations) + " stations " + std::to_string(sim.scanner.cols) + "x" +
                           std::to_string(sim.scanner.rows);
  pipeline::RegisterOptions tree_options;
  tree_options.global = false;  // as `register --no-global`
  tree_options.feature_cache_dir =
      std::filesystem::temp_directory_path() / ("scanreg-bench-global-" + std::to_string(::getpid()));
  pipeline::RegisterOptions global_options = tree_options;
  global_options.global = global_options.verify_all_links = true;  // as `register --global`
  Expected<pipeline::ProjectRegistration> tree =
      pipeline::RegisterScans(*scans, {}, tree_options, progress, cancel);
  Expected<pipeline::ProjectRegistration> global =
      pipeline::RegisterScans(*scans, {}, global_options, progress, cancel);
  std::filesystem::remove_all(tree_options.feature_cache_dir);
  if (!tree || !global) {
    table.Add({kSection, "street", 0.0, "", "failed: " + (tree ? global : tree).error().ToString()});
    return;
  }
  int extra = 0;
  for (const io::LinkRecord& l : global->links) extra += l.loop_check && l.status != io::LinkStatus::kFailed;
  AddPair(table, "street " + size, WorstError(*tree, *scans), WorstError(*global, *scans),
          "worst position error; --global: " + std::to_string(extra) + " loop-check links in the graph");

  // (b) Drift: one tree link in the middle of the chain off by 5 cm and 0.3 deg, on the --global run's links.
  pipeline::ProjectRegistration drift = *global;
  std::vector<io::LinkRecord*> tree_links;
  for (io::LinkRecord& l : drift.links)
    if (!l.loop_check && l.status != io::LinkStatus::kFailed) tree_links.push_back(&l);
  if (tree_links.empty()) return;
  io::LinkRecord& bad = *tree_links[tree_links.size() / 2];
  Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
  error.linear() = Eigen::AngleAxisd(0.3 / kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  error.translation() = Eigen::Vector3d(0.03, 0.04, 0.0);
  bad.parent_from_child = bad.parent_from_child * error;
  Rechain(*scans, &drift);
  pipeline::ProjectRegistration drift_global = drift;
  if (Status s = pipeline::RunGlobalRegistration(*scans, cancel, &drift_global); !s) {
    table.Add({kSection, "street drift", 0.0, "", "failed: " + s.error().ToString()});
    return;
  }
  AddPair(table, "street, drift in link " + bad.parent + "-" + bad.child, WorstError(drift, *scans),
          WorstError(drift_global, *scans), "5 cm / 0.3 deg injected");

  // (c) Failure case: one wrong extra link (1 m, 5 deg) between the first and last scan.
  pipeline::ProjectRegistration wrong = *global;
  io::LinkRecord fake = *tree_links.front();
  fake.loop_check = true;
  fake.parent = tree_links.front()->parent;
  fake.child = tree_links.back()->child;
  int p = -1, c = -1;
  for (std::size_t i = 0; i < scans->size(); ++i) {
    if ((*scans)[i].name == fake.parent) p = static_cast<int>(i);
    if ((*scans)[i].name == fake.child) c = static_cast<int>(i);
  }
  if (p < 0 || c < 0 || p == c) return;
  Eigen::Isometry3d off = Eigen::Isometry3d::Identity();
  off.linear() = Eigen::AngleAxisd(5.0 / kDeg, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  off.translation() = Eigen::Vector3d(1.0, 0.0, 0.0);
  fake.parent_from_child =
      (*(*scans)[p].reference_world_from_scan).inverse() * *(*scans)[c].reference_world_from_scan * off;
  wrong.links.push_back(fake);
  Rechain(*scans, &wrong);
  pipeline::ProjectRegistration wrong_global = wrong;
  if (Status s = pipeline::RunGlobalRegistration(*scans, cancel, &wrong_global); !s) return;
  int down = 0;
  for (const auto& g : wrong_global.global_links) down += g.down_weighted;
  AddPair(table, "street + wrong link " + fake.parent + "-" + fake.child, WorstError(wrong, *scans),
          WorstError(wrong_global, *scans),
          "1 m / 5 deg wrong extra link; down-weighted links: " + std::to_string(down));
}

std::filesystem::path RealData() {
  if (const char* env = std::getenv("SCANREG_REALDATA")) return env;
  return SCANREG_BENCH_REALDATA;
}

void Bunny(Table& table, bool quick) {
  const std::filesystem::path dir = RealData() / "stanford_bunny";
  Expected<std::vector<io::NamedPose>> poses = io::ReadBunConf(dir / "bun.conf");
  if (!poses) {
    table.Add(
        {kSection, "bunny --coarse none", 0.0, "", "skipped: " + poses.error().ToString() + " (set SCANREG_REALDATA)"});
    return;
  }
  NullProgress progress;
  CancelToken cancel;
  std::vector<Scan> scans;
  std::vector<Eigen::Vector3d> centroid;
  for (const io::NamedPose& p : *poses) {
    Expected<Scan> s = io::ReadPly(dir / p.scan, progress, cancel);
    if (!s) return table.Add({kSection, "bunny --coarse none", 0.0, "", "failed: " + s.error().ToString()});
    s->name = std::filesystem::path(p.scan).stem().string();
    s->reference_world_from_scan = p.world_from_scan;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    int n = 0;
    for (std::size_t k = 0; k < s->size(); ++k)
      if (s->valid[k]) c += s->points[k].cast<double>(), ++n;
    centroid.push_back(p.world_from_scan * (c / std::max(n, 1)));
    scans.push_back(std::move(*s));
  }
  pipeline::RegisterOptions o;
  o.from_current_poses = true;
  o.fine = pipeline::FineMethod::kEm;
  o.range_sigma_m = 0.0005;
  o.overlap_distance_m = 0.01;
  o.thresholds.max_rms_m = 0.002;
  o.thresholds.weak_rms_m = 0.001;
  o.root = "bun000";
  const int starts = quick ? 1 : 3;
  Worst tree_worst, global_worst;
  std::mt19937 rng(23);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int s = 0; s < starts; ++s) {
    for (std::size_t i = 0; i < scans.size(); ++i) {
      Eigen::Isometry3d move = Eigen::Isometry3d::Identity();
      if (scans[i].name != "bun000") {
        move.linear() =
            Eigen::AngleAxisd(3.0 / kDeg, Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized()).toRotationMatrix();
        move.translation() =
            centroid[i] - move.linear() * centroid[i] + 0.003 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      }
      scans[i].world_from_scan = move * *scans[i].reference_world_from_scan;
    }
    for (bool global : {false, true}) {
      o.global = global;
      Expected<pipeline::ProjectRegistration> r = pipeline::RegisterScans(scans, {}, o, progress, cancel);
      if (!r) return table.Add({kSection, "bunny --coarse none", 0.0, "", "failed: " + r.error().ToString()});
      const Worst w = WorstError(*r, scans);
      Worst& acc = global ? global_worst : tree_worst;
      acc.mm = std::max(acc.mm, w.mm);
      acc.deg = std::max(acc.deg, w.deg);
      acc.registered = w.registered;
    }
  }
  AddPair(table, "bunny 10 scans --coarse none --fine em", tree_worst, global_worst,
          "worst over " + std::to_string(starts) + " starts (3 deg / 3 mm off bun.conf) and scans");
}

}  // namespace

void RunGlobalBench(Table& table, bool quick) {
  Street(table, quick);
  Bunny(table, quick);
}

}  // namespace scanreg::bench
