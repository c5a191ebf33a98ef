// Pair registrations as independent jobs, to spread a large project over many processes or
// machines (issue 13, item 6):
//   register --plan DIR   features, matching and the candidate pairs as a single run makes them;
//                         DIR/plan.json lists one job per pair and the lengths resolved from the data;
//   pair-job DIR K        registers the scans of pair K to each other both ways (two scans loaded);
//   register --collect DIR  the scan order, loop checks, global step and report as a single run
//                         makes them, taking each pair registration from the jobs' results.
// A pair registration depends only on its two scans and the options, so the collected project is
// the single-process one; a pair the driver needs that no job holds (a pair by position, or one of
// the global step's pairs found at the registered poses) is registered while collecting.
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/common/expected.h"
#include "core/pipeline/register_options.h"
#include "core/pipeline/register_pair.h"

namespace scanreg::pipeline {

// How RegisterScans trades pair registrations with jobs (register_project.h).
struct PairExchange {
  // register --plan: receives the resolved options and the candidate pairs (i < j); RegisterScans
  // then returns after matching, without registering any pair.
  std::function<void(const RegisterOptions& resolved, const std::vector<std::pair<int, int>>& pairs)> planned;
  // register --collect: (parent, child) -> the job's registration, used instead of registering it.
  const std::map<std::pair<int, int>, PairResult>* results = nullptr;
};

struct PairJobPlan {
  std::filesystem::path project;   // the project file (absolute)
  std::string settings;            // the project's registration settings when planned (JSON text)
  std::vector<std::string> scans;  // names, in project order
  // The lengths the registration resolved from all the scans (scale_defaults.h): a job sees two.
  double range_sigma_m = 0, overlap_distance_m = 0, geometric_voxel_m = 0;
  std::vector<std::pair<int, int>> pairs;  // job k registers pairs[k] (i < j) both ways
};

// DIR/plan.json (atomic; DIR and DIR/results created). Errors name the file.
Status WritePairJobPlan(const PairJobPlan& plan, const std::filesystem::path& dir);
// Errors name the file and say to plan again.
Expected<PairJobPlan> ReadPairJobPlan(const std::filesystem::path& dir);
// The project's settings as the plan records them; an error when they differ from the plan's.
std::string SettingsText(const std::map<std::string, std::string>& settings);
Status CheckSameSettings(const PairJobPlan& plan, const std::map<std::string, std::string>& settings,
                         const std::vector<std::string>& scan_names);
// options with the plan's lengths, so that two scans resolve as the whole project did.
RegisterOptions WithPlanLengths(RegisterOptions options, const PairJobPlan& plan);

// Job k: scan a (plan.scans[pairs[k].first]) registered to b and b to a, as RegisterScans would:
// [0] parent a, child b; [1] parent b, child a.
Expected<std::array<PairResult, 2>> RunPairJob(const Scan& a, const Scan& b, const RegisterOptions& options,
                                               const CancelToken& cancel);
// DIR/results/pair-K.json (atomic), tied to the plan.
Status WritePairJobResult(const std::filesystem::path& dir, const PairJobPlan& plan, int k,
                          const std::array<PairResult, 2>& result);
// Every job's result found in DIR/results, by (parent, child) scan index. A missing, unreadable or
// foreign (another plan's) result is left out and described in *problems.
std::map<std::pair<int, int>, PairResult> ReadPairJobResults(const std::filesystem::path& dir,
                                                             const PairJobPlan& plan,
                                                             std::vector<std::string>* problems);

}  // namespace scanreg::pipeline
