// scanreg-cli register: automatic registration of a project (W §2), with the evidence printed.
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "app/cli_commands.h"
#include "app/cli_georef.h"
#include "app/cli_util.h"
#include "core/common/skipped_pair.h"
#include "core/geometry/transform.h"
#include "core/io/project.h"
#include "core/io/project_lock.h"
#include "core/pipeline/pair_jobs.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/scan_store.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/register_settings.h"

namespace scanreg::cli {
namespace {

constexpr double kDeg = 180.0 / M_PI;

void PrintText(const pipeline::ProjectRegistration& r, const std::vector<Scan>& scans,
               const std::vector<pipeline::ReferenceError>& errors) {
  const int n = static_cast<int>(scans.size());
  const bool by_overlap = !r.links.empty() && r.links.front().method.rfind("none+", 0) == 0;  // --coarse none
  std::printf(by_overlap ? "\noverlap at the current poses (per mille of j's samples near i)\n%8s"
                         : "\nconfusion matrix C(i,j): matches of i's features in j (diagonal: features of i)\n%8s",
              "");
  for (int j = 0; j < n; ++j) std::printf(" %7s", scans[j].name.c_str());
  std::printf("\n");
  for (int i = 0; i < n; ++i) {
    std::printf("%8s", scans[i].name.c_str());
    for (int j = 0; j < n; ++j) {
      if (r.confusion(i, j) == kSkippedPair) std::printf(" %7s", "-");  // not a candidate pair
      else std::printf(" %7d", r.confusion(i, j));
    }
    std::printf("\n");
  }
  std::printf("\nscan order (root %s):\n", scans[r.root].name.c_str());
  for (const auto& s : r.scans) {
    if (s.parent >= 0) std::printf("  %s <- %s\n", scans[s.parent].name.c_str(), s.name.c_str());
  }
  std::printf("\n%-8s %-8s %-22s %11s %8s %11s %10s %8s %9s %10s %8s %6s %7s  %-6s %s\n", "parent", "child", "method",
              "sift+fpfh", "reliable", "inl s+f", "consistent", "RMS mm", "overlap %", "conflict %", "moving %", "iter", "time s", "status", "reason");
  for (const io::LinkRecord& l : r.links) {
    const std::string matches = std::to_string(l.matches) + "+" + std::to_string(l.geometric_matches);
    const std::string inliers =
        std::to_string(l.ransac_inliers - l.geometric_inliers) + "+" + std::to_string(l.geometric_inliers);
    std::printf("%-8s %-8s %-22s %11s %8d %11s %10d %8.1f %9.1f %10.1f %8.1f %6d %7.2f  %-6s %s\n", l.parent.c_str(),
                l.child.c_str(), (l.loop_check ? "check:" + l.method : l.method).c_str(), matches.c_str(), l.reliable,
                inliers.c_str(), l.consistent, l.rms_m * 1000, l.overlap * 100, l.conflict * 100, l.moving * 100, l.iterations,
                l.seconds, io::LinkStatusName(l.status), l.reason.c_str());
  }
  bool any_reference = false;
  for (const auto& e : errors) any_reference |= e.available;
  const bool consistency = r.consistency.has_value();
  if (consistency) {
    std::printf("\nconsistency (no ground truth): robust RMS of the point-to-plane residuals over %d overlapping pairs "
                "(capped at %.2f mm): %.3f mm at the start poses -> %.3f mm%s%s\n",
                r.consistency->pairs, 1e3 * r.consistency->cutoff_m, 1e3 * r.consistency->start_rms_m,
                1e3 * r.consistency->result_rms_m, r.consistency->multiview ? " (multi-view fine step)" : "",
                r.consistency->refused ? "; less consistent than the start: REFUSED, the start poses are kept" : "");
  }
  std::printf("\n%-8s %-13s", "scan", "status");
  if (consistency) std::printf(" %9s %9s %8s", "start mm", "resid mm", "cond");
  if (any_reference) std::printf(" %12s %12s %12s %12s", "coarse mm", "coarse deg", "fine mm", "fine deg");
  std::printf("\n");
  for (std::size_t i = 0; i < r.scans.size(); ++i) {
    const auto& s = r.scans[i];
    std::printf("%-8s %-13s", s.name.c_str(),
                s.registered ? (static_cast<int>(i) == r.root ? "root" : "registered")
                : s.unverified ? "NOT VERIFIED"
                               : "UNREGISTERED");
    if (consistency) {
      auto mm = [](double v) { return v < 0 ? std::string("-") : std::to_string(1e3 * v).substr(0, 6); };
      const std::string cond = s.conditioning < 0 ? "-" : std::to_string(s.conditioning).substr(0, 6);
      std::printf(" %9s %9s %8s", mm(s.start_consistency_m).c_str(), mm(s.consistency_m).c_str(), cond.c_str());
    }
    if (any_reference && errors[i].available) {
      if (errors[i].has_coarse) {
        std::printf(" %12.1f %12.4f", errors[i].coarse_position_m * 1000, errors[i].coarse_angle_rad * kDeg);
      } else {
        std::printf(" %12s %12s", "-", "-");
      }
      std::printf(" %12.1f %12.4f", errors[i].position_m * 1000, errors[i].angle_rad * kDeg);
    }
    if (!s.registered) std::printf("  %s", s.reason.c_str());
    std::printf("\n");
  }
  if (!r.global_links.empty()) {
    std::printf("\nglobal registration (pose graph, Cauchy kernel): link residuals before -> after\n");
    for (const auto& g : r.global_links) {
      std::printf("  %-8s %-8s %8.1f mm %8.4f deg  ->  %8.1f mm %8.4f deg  weight %.3f%s\n", g.parent.c_str(),
                  g.child.c_str(), g.translation_before_m * 1000, g.rotation_before_rad * kDeg,
                  g.translation_after_m * 1000, g.rotation_after_rad * kDeg, g.weight,
                  g.down_weighted ? "  DOWN-WEIGHTED" : "");
    }
  }
  std::printf("\npairs matched: %d of %d%s\n", r.pairs_matched, r.pairs_possible,
              r.pairs_matched < r.pairs_possible ? " (candidate pairs; the others are - above)" : "");
  if (r.pairs_from_jobs > 0) std::printf("pair registrations from the pair jobs: %d\n", r.pairs_from_jobs);
  std::printf("time: features %.1f s (%d from cache), matching %.1f s, pairs %.1f s, total %.1f s\n",
              r.seconds_features, r.features_from_cache, r.seconds_matching, r.seconds_pairs, r.seconds_total);
}

nlohmann::json ToJson(const pipeline::ProjectRegistration& r, const std::vector<Scan>& scans,
                      const std::vector<pipeline::ReferenceError>& errors) {
  using nlohmann::json;
  json confusion = json::array();
  for (int i = 0; i < r.confusion.rows(); ++i) {
    json row = json::array();
    for (int j = 0; j < r.confusion.cols(); ++j)
      row.push_back(r.confusion(i, j) == kSkippedPair ? json(nullptr) : json(r.confusion(i, j)));  // null: not matched
    confusion.push_back(row);
  }
  json links = json::array();
  for (const io::LinkRecord& l : r.links) {
    links.push_back({{"parent", l.parent},
                     {"child", l.child},
                     {"method", l.method},
                     {"status", io::LinkStatusName(l.status)},
                     {"reason", l.reason},
                     {"matches", l.matches},
                     {"geometric_matches", l.geometric_matches},
                     {"reliable", l.reliable},
                     {"ransac_inliers", l.ransac_inliers},
                     {"geometric_inliers", l.geometric_inliers},
                     {"consistent", l.consistent},
                     {"rms_m", l.rms_m},
                     {"overlap", l.overlap},
                     {"conflict", l.conflict},
                     {"moving", l.moving},
                     {"iterations", l.iterations},
                     {"seconds", l.seconds},
                     {"loop_check", l.loop_check}});
  }
  json out_scans = json::array();
  for (std::size_t i = 0; i < r.scans.size(); ++i) {
    const auto& s = r.scans[i];
    const auto m = RowMajorFromIsometry(s.world_from_scan);
    json js{{"name", s.name},
            {"registered", s.registered},
            {"status", s.registered ? "registered" : s.unverified ? "not verified" : "unregistered"},
            {"parent", s.parent >= 0 ? json(scans[s.parent].name) : json(nullptr)},
            {"reason", s.reason},
            {"world_from_scan", std::vector<double>(m.begin(), m.end())}};
    if (r.consistency) {
      js["start_consistency_m"] = s.start_consistency_m;
      js["consistency_m"] = s.consistency_m;
      js["conditioning"] = s.conditioning;
    }
    if (errors[i].available) {
      js["error_position_m"] = errors[i].position_m;
      js["error_angle_deg"] = errors[i].angle_rad * kDeg;
      if (errors[i].has_coarse) {
        js["coarse_error_position_m"] = errors[i].coarse_position_m;
        js["coarse_error_angle_deg"] = errors[i].coarse_angle_rad * kDeg;
      }
    }
    out_scans.push_back(js);
  }
  std::vector<std::string> names;
  for (const Scan& s : scans) names.push_back(s.name);
  json out = json{{"scans", out_scans},
              {"names", names},
              {"root", scans[r.root].name},
              {"confusion", confusion},
              {"pairs_matched", r.pairs_matched},
              {"pairs_possible", r.pairs_possible},
              {"pairs_from_jobs", r.pairs_from_jobs},
              {"links", links},
              {"seconds",
               {{"features", r.seconds_features},
                {"matching", r.seconds_matching},
                {"pairs", r.seconds_pairs},
                {"total", r.seconds_total}}}};
  if (r.consistency) {
    out["consistency"] = {{"pairs", r.consistency->pairs},
                          {"cutoff_m", r.consistency->cutoff_m},
                          {"start_rms_m", r.consistency->start_rms_m},
                          {"result_rms_m", r.consistency->result_rms_m},
                          {"multiview", r.consistency->multiview},
                          {"refused", r.consistency->refused}};
  }
  return out;
}

}  // namespace

int RegisterAndReport(io::Project& project, pipeline::RegisterOptions options, bool json,
                      const pipeline::PairExchange* exchange, std::size_t memory_budget) {
  // One writer at a time: a second register on this project refuses now, not after minutes of work.
  Expected<io::ProjectLock> lock = io::ProjectLock::Acquire(project.file, "scanreg-cli register");
  if (!lock) return Fail(lock.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  pipeline::ScanStore store =
      pipeline::ProjectScanStore(project, memory_budget > 0 ? memory_budget : pipeline::DefaultMemoryBudget());
  auto result = pipeline::RegisterProjectScans(project, store, options, progress, cancel, exchange);
  if (!result) return Fail(result.error());
  if (Status s = io::SaveProject(project, project.file); !s) return Fail(s.error());
  const std::vector<Scan>& scans = store.heads();
  const auto errors = pipeline::ReferenceErrors(*result, scans);
  if (json) {
    nlohmann::json out = ToJson(*result, scans, errors);
    out["memory"] = {{"budget_bytes", store.budget_bytes()},
                     {"peak_bytes", store.peak_bytes()},
                     {"scan_reads", store.reads()},
                     {"surface_builds", store.surface_builds()}};
    if (!project.control.empty()) out["georef"] = GeorefJson(project, *result);
    std::printf("%s\n", out.dump(2).c_str());
  } else {
    PrintText(*result, scans, errors);
    std::printf("scans: read %d times for %zu scans, dense-ICP surfaces built %d times, at most %s of both held "
                "(memory budget %s)\n",
                store.reads(), scans.size(), store.surface_builds(), FormatBytes(store.peak_bytes()).c_str(),
                FormatBytes(store.budget_bytes()).c_str());
    PrintGeoref(project, *result);
  }
  int unregistered = 0, unverified = 0;
  for (const auto& s : result->scans) {
    unregistered += !s.registered && !s.unverified;
    unverified += !s.registered && s.unverified;
  }
  if (unregistered + unverified > 0) {
    std::string what;
    if (unregistered > 0) what = std::to_string(unregistered) + " could not be registered";
    if (unverified > 0)
      what += (what.empty() ? "" : " and ") + std::to_string(unverified) +
              " were placed but not verified (accept a link with `scanreg-cli link PROJECT PARENT CHILD --accept` "
              "when its pose is right)";
    what = "of " + std::to_string(result->scans.size()) + " scans, " + what;
    std::fprintf(stderr, "scanreg-cli: %s (reasons above); project saved\n", what.c_str());
    return 3;
  }
  if (!project.control.empty() && !result->georeferenced) {
    std::fprintf(stderr, "scanreg-cli: georeferencing failed: %s; the registration is saved in the root scan's frame\n",
                 result->georef_error.c_str());
    return 4;
  }
  return 0;
}

int RunRegister(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp(
      "register",
      "PROJECT.scanreg.json [options]   registers every scan and saves the project; options default to the "
      "project's saved settings",
      argv,
      {{"root", true, false, "NAME     root scan of the scan order (default: tail of the heaviest edge)"},
       {"parent", true, true, "SCAN=PARENT   register SCAN to PARENT (repeatable; saved in the project)"},
       {"coarse", true, false,
        "epnp|3d|none   coarse method: EPnP on the virtual plane (W), 3D-3D RANSAC (default), or "
        "none: refine from the current poses, linking the scans that overlap there (the "
        "default when every scan has an imported pose)"},
       {"fine", true, false,
        "keypoints|dense|em|projective-icp   fine method: keypoint ICP (W), dense point-to-plane "
        "ICP (default), S's EM on the range images, or projective ICP (S's [15])"},
       {"features", true, false,
        "both|sift|fpfh   correspondences: SIFT on the reflectance (W), FPFH on the geometry, or "
        "both into one estimator (default); levelled scans also get plan-view poses"},
       {"overlap-distance", true, false,
        "METRES   a child point this near the parent's surface overlaps; the other lengths "
        "(ICP samples, inlier and loop tolerances, RMS limits) follow it (default: from the data, "
        "max(8 x noise, 2 x point spacing, extent / 100); with --coarse none also how far apart the "
        "current poses are)"},
       {"ratio", true, false, "T        descriptor ratio threshold t_des (default 0.66, W)"},
       {"sift-half-size-step", true, false,
        "DEG      detect SIFT on a half-size panorama when a scan seen from one spot has its cells at most DEG "
        "apart in both directions: OpenCV's SIFT doubles its input, so a finely sampled panorama (the paper's "
        "3000 x 750, 0.12°) gives the same blobs at a quarter of the pixels (default 0.18; 0: always full size)"},
       {"coarse-scale", true, false,
        "X        also FPFH descriptors at X times the voxel, matched scale with scale: stations far apart "
        "(a busy street 12 m apart: 6 of 6 scans instead of 2) — but in repetitive interiors they also "
        "support a corridor turned 180° (default 0: the fine scale only; 3 for wide spacing outdoors)"},
       {"noise", true, false, "METRES   scanner range noise sigma (default: from the data, the scans' local plane residuals)"},
       {"no-cache", false, false, "       do not read or write the feature cache"},
       {"global", false, false,
        "       global registration: pose graph over every link, all links loop-checked (default)"},
       {"no-global", false, false, "       no global registration: chain the pairwise links along the tree only"},
       {"multiview", false, false,
        "       with --coarse none: after the pose graph, one fine step over every overlapping pair at once, "
        "taken when it is more consistent (default)"},
       {"no-multiview", false, false, "       with --coarse none: the pose graph's poses only"},
       {"keep-imported", false, false,
        "       keep the imported poses (from --poses or the scan files' headers) fixed "
        "and place the other scans relative to them"},
       {"refine-imported", false, false, "       re-estimate imported poses (the default)"},
       {"only-unregistered", false, false,
        "       place only the scans that are not registered; every registered scan keeps its pose and link"},
       {"json", false, false, "       print the result as JSON"},
       ControlOptions()[0], ControlOptions()[1],
       {"sphere-radius", true, false, "METRES   radius of the sphere targets (default 0.0725: 145 mm spheres)"},
       {"checker-size", true, false,
        "METRES   side of the checkerboard targets' 2 x 2 pattern (default 0.2; 0: do not look for them)"},
       {"control-tolerance", true, false,
        "METRES   control residual tolerance: green below half, orange up to it, red beyond (default 0.01)"},
       {"levelled", true, false,
        "DEG      the scans are levelled (tilt compensator) to this accuracy, a constraint of the "
        "georeferencing; a scan whose file carried a pose is levelled through that pose's vertical "
        "(default 0: not levelled)"},
       {"candidates", true, false,
        "K        match each scan's features with its K best-voted scans, its capture-order neighbour "
        "and the user's pairs only (default 10; 0: every pair)"},
       {"global-partners", true, false,
        "K        the global step refines each scan's K largest overlaps at the registered poses besides "
        "the tree's links: faster on big projects, less accurate (default 0: every overlapping pair)"},
       {"plan", true, false,
        "DIR      prepare the features and candidate pairs, write DIR/plan.json with one job per pair "
        "(run each with scanreg-cli pair-job DIR K, e.g. as a Slurm array), and stop"},
       {"collect", true, false,
        "DIR      register with the pair registrations of the jobs planned in DIR (the same result as "
        "without them; a pair with no job result is registered here)"},
       {"memory-budget", true, false,
        "SIZE     hold at most this much of full scans and dense-ICP surfaces in memory (e.g. 6G, 800M); "
        "the others are read again from the binary scan cache, or built again, when a pair needs them "
        "(default: a quarter of the RAM). The result does not depend on it"}},
      &code);
  if (!args) return code;
  if (args->positional().size() != 1) {
    return Fail(MakeError(ErrorCode::kInvalidArgument, "register: give exactly one project file"));
  }
  for (const auto& [yes, no] :
       {std::make_pair("global", "no-global"), std::make_pair("multiview", "no-multiview"),
        std::make_pair("keep-imported", "refine-imported")}) {
    if (args->Has(yes) && args->Has(no)) {
      return Fail(MakeError(ErrorCode::kInvalidArgument,
                            std::string("register: give --") + yes + " or --" + no + ", not both"));
    }
  }
  auto project = io::LoadProject(args->positional()[0]);
  if (!project) return Fail(project.error());
  // The project's saved settings, then the flags given now (saved for the next run).
  auto options = pipeline::ProjectRegisterOptions(*project);
  if (!options) return Fail(MakeError(options.error().code, project->file.string() + ": " + options.error().message));
  for (const pipeline::RegisterSetting& setting : pipeline::RegisterSettings()) {
    std::optional<std::string> value;
    if (setting.boolean) {
      if (args->Has(setting.flag)) value = "true";
      if (args->Has(std::string("no-") + setting.flag)) value = "false";
      if (std::string(setting.flag) == "keep-imported" && args->Has("refine-imported")) value = "false";
    } else {
      value = args->Get(setting.flag);
    }
    if (!value) continue;
    if (Status s = pipeline::ApplyRegisterSetting(setting, *value, &*options); !s) {
      return Fail(MakeError(s.error().code, "register: --" + std::string(setting.flag) + ": " + s.error().message));
    }
  }
  if (auto root = args->Get("root")) options->root = *root;
  if (Status s = ImportControl(*args, &*project); !s) return Fail(s.error());
  if (args->Has("only-unregistered")) {
    for (const io::ProjectScan& s : project->scans)
      if (!s.registered) options->only_scans.push_back(s.name);
    if (options->only_scans.empty()) {
      std::printf("every scan is registered; nothing to do (--only-unregistered)\n");
      return 0;
    }
  }
  for (const std::string& p : args->GetAll("parent")) {
    const auto eq = p.find('=');
    const int child = eq == std::string::npos ? -1 : project->FindScan(p.substr(0, eq));
    const int parent = eq == std::string::npos ? -1 : project->FindScan(p.substr(eq + 1));
    if (child < 0 || parent < 0 || child == parent) {
      return Fail(
          MakeError(ErrorCode::kInvalidArgument,
                    "register: --parent '" + p + "' must be SCAN=PARENT with two different scans of the project"));
    }
    project->scans[child].parent_override = project->scans[parent].name;
  }
  if (!args->Has("no-cache")) options->feature_cache_dir = pipeline::ProjectCacheDir(*project);
  int imported = 0;
  for (const io::ProjectScan& s : project->scans) imported += s.registered && s.imported_pose;
  if (imported > 0) {
    std::fprintf(stderr, "register: %d scan(s) have imported poses: %s\n", imported,
                 options->keep_imported ? "kept fixed; the other scans are placed relative to them (--keep-imported)"
                 : options->from_current_poses
                     ? "refined from where they are (--coarse none; --keep-imported keeps them fixed)"
                     : "re-estimated from the scans' features (--keep-imported keeps them fixed)");
  }
  pipeline::StoreRegisterSettings(*options, &project->settings);
  if (args->Has("plan") && args->Has("collect"))
    return Fail(MakeError(ErrorCode::kInvalidArgument, "register: give --plan or --collect, not both"));
  std::size_t budget = 0;
  if (auto text = args->Get("memory-budget")) {
    Expected<std::size_t> parsed = pipeline::ParseMemoryBudget(*text);
    if (!parsed) return Fail(MakeError(parsed.error().code, "register: --memory-budget: " + parsed.error().message));
    budget = *parsed;
  }
  if (auto dir = args->Get("plan")) return PlanPairJobs(*project, *options, *dir, budget);
  if (auto dir = args->Get("collect")) {
    std::map<std::pair<int, int>, pipeline::PairResult> results;
    if (Status s = CollectPairJobs(*project, *dir, &*options, &results); !s) return Fail(s.error());
    pipeline::PairExchange exchange;
    exchange.results = &results;
    return RegisterAndReport(*project, *options, args->Has("json"), &exchange, budget);
  }
  return RegisterAndReport(*project, *options, args->Has("json"), nullptr, budget);
}

}  // namespace scanreg::cli
