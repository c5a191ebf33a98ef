#include "core/pipeline/pair_jobs.h"

#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/common/atomic_file.h"
#include "core/common/hash.h"
#include "core/features/confusion.h"
#include "core/io/project.h"
#include "core/io/text_parse.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/scale_defaults.h"
#include "core/registration/geometric_features.h"

namespace scanreg::pipeline {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kFormat = 1;

Status WriteAtomically(const fs::path& file, const std::string& text) {
  AtomicFile out(file);
  if (Status s = out.Open(); !s) return s;
  if (Status s = out.Write(text); !s) return s;
  return out.Commit();
}

Expected<json> ReadJson(const fs::path& file) {
  Expected<std::string> text = io::ReadWholeFile(file);
  if (!text) return text.error();
  try {
    return json::parse(*text);
  } catch (const json::exception& e) {
    return MakeError(ErrorCode::kParseError, file.string() + ": not valid JSON (" + e.what() + ")");
  }
}

// Ties a result to its plan: the settings, scans, lengths and pairs.
std::string PlanKey(const PairJobPlan& plan) {
  Hasher h(kFormat);
  h.Add(plan.settings.data(), plan.settings.size());
  for (const std::string& s : plan.scans) h.Add(s.data(), s.size() + 1);
  for (double v : {plan.range_sigma_m, plan.overlap_distance_m, plan.geometric_voxel_m}) h.Add(&v, sizeof v);
  for (const auto& [i, j] : plan.pairs) {
    h.Add(&i, sizeof i);
    h.Add(&j, sizeof j);
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h.Digest()));
  return buf;
}

fs::path ResultFile(const fs::path& dir, int k) {
  char name[32];
  std::snprintf(name, sizeof name, "pair-%05d.json", k);
  return dir / "results" / name;
}

json PairResultToJson(const PairResult& r) {
  return {{"link", io::LinkToJson(r.link)},
          {"coarse_parent_from_child", io::PoseToJson(r.coarse_parent_from_child)},
          {"coarse_ok", r.coarse_ok},
          {"coarse_inlier_matches", r.coarse_inlier_matches},
          {"needs_loop", r.needs_loop},
          {"needs_loop_if_checkable", r.needs_loop_if_checkable},
          {"same_spot", r.same_spot},
          {"surfaces_only", r.surfaces_only},
          {"weak_support", r.weak_support},
          {"violation_rate", r.violation_rate}};
}

Expected<PairResult> PairResultFromJson(const json& j, const std::string& where) {
  if (!j.is_object() || !j.contains("link") || !j.contains("coarse_parent_from_child"))
    return MakeError(ErrorCode::kParseError, where + ": not a pair result");
  PairResult r;
  Expected<io::LinkRecord> link = io::LinkFromJson(j["link"], where);
  if (!link) return link.error();
  r.link = *link;
  Expected<Eigen::Isometry3d> coarse = io::PoseFromJson(j["coarse_parent_from_child"], where + " coarse pose");
  if (!coarse) return coarse.error();
  r.coarse_parent_from_child = *coarse;
  try {
    r.coarse_ok = j.at("coarse_ok").get<bool>();
    r.coarse_inlier_matches = j.at("coarse_inlier_matches").get<std::vector<int>>();
    r.needs_loop = j.at("needs_loop").get<bool>();
    r.needs_loop_if_checkable = j.value("needs_loop_if_checkable", false);
    r.same_spot = j.value("same_spot", false);
    r.surfaces_only = j.value("surfaces_only", false);
    r.weak_support = j.value("weak_support", false);
    r.violation_rate = j.value("violation_rate", 0.0);
  } catch (const json::exception& e) {
    return MakeError(ErrorCode::kParseError, where + ": " + e.what());
  }
  return r;
}

}  // namespace

std::string SettingsText(const std::map<std::string, std::string>& settings) { return json(settings).dump(); }

Status WritePairJobPlan(const PairJobPlan& plan, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir / "results", ec);
  if (ec) return MakeError(ErrorCode::kIoError, (dir / "results").string() + ": cannot create the folder (" + ec.message() + ")");
  json pairs = json::array();
  for (const auto& [i, j] : plan.pairs) pairs.push_back({i, j});
  const json out{{"format", kFormat},
                 {"key", PlanKey(plan)},
                 {"project", plan.project.string()},
                 {"settings", plan.settings},
                 {"scans", plan.scans},
                 {"range_sigma_m", plan.range_sigma_m},
                 {"overlap_distance_m", plan.overlap_distance_m},
                 {"geometric_voxel_m", plan.geometric_voxel_m},
                 {"jobs", pairs.size()},
                 {"pairs", pairs}};
  return WriteAtomically(dir / "plan.json", out.dump(1) + "\n");
}

Expected<PairJobPlan> ReadPairJobPlan(const fs::path& dir) {
  const fs::path file = dir / "plan.json";
  Expected<json> j = ReadJson(file);
  if (!j) return MakeError(j.error().code, j.error().message + "; run register --plan " + dir.string() + " first");
  const Error bad = MakeError(ErrorCode::kParseError, file.string() + ": not a pair-job plan of this version; plan again "
                                                                      "(register PROJECT --plan " + dir.string() + ")");
  PairJobPlan plan;
  try {
    if (j->at("format").get<int>() != kFormat) return bad;
    plan.project = j->at("project").get<std::string>();
    plan.settings = j->at("settings").get<std::string>();
    plan.scans = j->at("scans").get<std::vector<std::string>>();
    plan.range_sigma_m = j->at("range_sigma_m").get<double>();
    plan.overlap_distance_m = j->at("overlap_distance_m").get<double>();
    plan.geometric_voxel_m = j->at("geometric_voxel_m").get<double>();
    for (const json& p : j->at("pairs")) {
      const int a = p.at(0).get<int>(), b = p.at(1).get<int>();
      if (a < 0 || b <= a || b >= static_cast<int>(plan.scans.size())) return bad;
      plan.pairs.emplace_back(a, b);
    }
    if (j->at("key").get<std::string>() != PlanKey(plan)) return bad;  // edited by hand or damaged
  } catch (const json::exception&) {
    return bad;
  }
  return plan;
}

Status CheckSameSettings(const PairJobPlan& plan, const std::map<std::string, std::string>& settings,
                         const std::vector<std::string>& scan_names) {
  if (scan_names != plan.scans)
    return MakeError(ErrorCode::kInvalidArgument,
                     "the project's scans are not the ones planned (scans added, removed or renamed since); plan again");
  if (SettingsText(settings) != plan.settings)
    return MakeError(ErrorCode::kInvalidArgument,
                     "the project's registration settings changed since the plan (planned: " + plan.settings +
                         ", now: " + SettingsText(settings) + "); plan again, or register without the plan");
  return Status::Ok();
}

RegisterOptions WithPlanLengths(RegisterOptions options, const PairJobPlan& plan) {
  options.range_sigma_m = plan.range_sigma_m;
  options.overlap_distance_m = plan.overlap_distance_m;
  if (plan.geometric_voxel_m > 0) options.geometric.voxel_m = plan.geometric_voxel_m;
  return options;
}

Expected<std::array<PairResult, 2>> RunPairJob(const Scan& a, const Scan& b, const RegisterOptions& raw_options,
                                               const CancelToken& cancel) {
  const Expected<RegisterOptions> resolved = ResolveLengths(raw_options, {&a, &b});
  if (!resolved) return resolved.error();
  const RegisterOptions& options = *resolved;
  std::array<PreparedScan, 2> prepared;
  for (int k = 0; k < 2; ++k) {
    bool cached = false;
    if (Status s = PrepareScanFeatures(k == 0 ? a : b, options, &prepared[k], &cached, cancel); !s) return s.error();
  }
  // As RegisterScans matches a pair: SIFT both ways, FPFH with the earlier scan as parent.
  std::vector<FeatureMatch> sift_ab, sift_ba;
  if (UsesSift(options.features)) {
    NullProgress quiet;
    Expected<MatchTable> table =
        MatchPairs({prepared[0].features, prepared[1].features}, {{0, 1}}, options.match, quiet, cancel);
    if (!table) return table.error();
    sift_ab = BothWays(*table, 0, 1);
    sift_ba = BothWays(*table, 1, 0);
  }
  std::vector<GeometricMatch> fpfh_ab, fpfh_ba;
  if (UsesGeometric(options.features)) {
    fpfh_ab = MatchGeometric(prepared[0].geometric, prepared[1].geometric);
    fpfh_ba = fpfh_ab;
    for (GeometricMatch& g : fpfh_ba) std::swap(g.parent, g.child);
  }
  std::array<PairResult, 2> out{RegisterPair(prepared[0], prepared[1], sift_ab, fpfh_ab, options, cancel),
                                RegisterPair(prepared[1], prepared[0], sift_ba, fpfh_ba, options, cancel)};
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "pair job cancelled");
  return out;
}

Status WritePairJobResult(const fs::path& dir, const PairJobPlan& plan, int k, const std::array<PairResult, 2>& result) {
  const json out{{"format", kFormat},
                 {"plan", PlanKey(plan)},
                 {"pair", {plan.pairs.at(k).first, plan.pairs.at(k).second}},
                 {"results", {PairResultToJson(result[0]), PairResultToJson(result[1])}}};
  return WriteAtomically(ResultFile(dir, k), out.dump() + "\n");
}

std::map<std::pair<int, int>, PairResult> ReadPairJobResults(const fs::path& dir, const PairJobPlan& plan,
                                                             std::vector<std::string>* problems) {
  std::map<std::pair<int, int>, PairResult> out;
  const std::string key = PlanKey(plan);
  for (int k = 0; k < static_cast<int>(plan.pairs.size()); ++k) {
    const fs::path file = ResultFile(dir, k);
    const auto [a, b] = plan.pairs[k];
    const std::string job = "job " + std::to_string(k) + " (" + plan.scans[a] + ", " + plan.scans[b] + ")";
    if (!fs::exists(file)) {
      problems->push_back(job + ": no result (not run, or it failed)");
      continue;
    }
    Expected<json> j = ReadJson(file);
    if (!j) {
      problems->push_back(job + ": " + j.error().message);
      continue;
    }
    if (!j->is_object() || j->value("plan", "") != key || !j->contains("results") || !(*j)["results"].is_array() ||
        (*j)["results"].size() != 2) {
      problems->push_back(job + ": " + file.string() + " belongs to another plan or is damaged");
      continue;
    }
    Expected<PairResult> ab = PairResultFromJson((*j)["results"][0], file.string());
    Expected<PairResult> ba = PairResultFromJson((*j)["results"][1], file.string());
    if (!ab || !ba) {
      problems->push_back(job + ": " + (!ab ? ab.error().message : ba.error().message));
      continue;
    }
    if (ab->link.parent != plan.scans[a] || ab->link.child != plan.scans[b] || ba->link.parent != plan.scans[b] ||
        ba->link.child != plan.scans[a]) {
      problems->push_back(job + ": " + file.string() + " holds other scans' links");
      continue;
    }
    out[{a, b}] = std::move(*ab);
    out[{b, a}] = std::move(*ba);
  }
  return out;
}

}  // namespace scanreg::pipeline
