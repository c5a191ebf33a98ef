// scanreg-cli register --plan DIR, pair-job DIR K, register --collect DIR: a registration spread
// over processes or machines (issue 13, item 6; core/pipeline/pair_jobs.h).
#include <cstdio>
#include <cstdlib>
#include <string>

#include "app/cli_commands.h"
#include "app/cli_util.h"
#include "core/io/project_lock.h"
#include "core/pipeline/pair_jobs.h"
#include "core/pipeline/project_scans.h"
#include "core/pipeline/register_project.h"
#include "core/pipeline/register_settings.h"
#include "core/pipeline/scan_store.h"

namespace scanreg::cli {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> ScanNames(const io::Project& project) {
  std::vector<std::string> names;
  for (const io::ProjectScan& s : project.scans) names.push_back(s.name);
  return names;
}

}  // namespace

int PlanPairJobs(io::Project& project, pipeline::RegisterOptions options, const fs::path& dir,
                 std::size_t memory_budget) {
  Expected<io::ProjectLock> lock = io::ProjectLock::Acquire(project.file, "scanreg-cli register --plan");
  if (!lock) return Fail(lock.error());
  TerminalProgress progress;
  CancelToken& cancel = InterruptToken();
  pipeline::ScanStore store =
      pipeline::ProjectScanStore(project, memory_budget > 0 ? memory_budget : pipeline::DefaultMemoryBudget());
  pipeline::PairJobPlan plan;
  plan.project = fs::absolute(project.file).lexically_normal();
  plan.settings = pipeline::SettingsText(project.settings);
  plan.scans = ScanNames(project);
  pipeline::PairExchange exchange;
  exchange.planned = [&](const pipeline::RegisterOptions& resolved, const std::vector<std::pair<int, int>>& pairs) {
    plan.range_sigma_m = resolved.range_sigma_m;
    plan.overlap_distance_m = resolved.overlap_distance_m;
    plan.geometric_voxel_m = resolved.geometric.voxel_m;
    plan.pairs = pairs;
  };
  auto result = pipeline::RegisterProjectScans(project, store, options, progress, cancel, &exchange);
  if (!result) return Fail(result.error());
  if (plan.pairs.empty()) return Fail(MakeError(ErrorCode::kFailed, "register --plan: no pair to register"));
  // The settings the jobs and the collect read are the ones planned.
  if (Status s = io::SaveProject(project, project.file); !s) return Fail(s.error());
  if (Status s = pipeline::WritePairJobPlan(plan, dir); !s) return Fail(s.error());
  const int jobs = static_cast<int>(plan.pairs.size());
  const std::string d = dir.string();
  std::printf("planned %d pair jobs (%d of %d pairs; features cached beside the project) in %s\n"
              "run each job:   scanreg-cli pair-job %s K    for K = 0 .. %d, in any order, on any machine that sees "
              "the project, its scans and its .scanreg-cache at the same path\n"
              "  with Slurm:   sbatch --wait --array=0-%d /usr/share/scanreg/slurm/pair-jobs.sbatch %s\n"
              "  locally:      seq 0 %d | xargs -P 2 -I K scanreg-cli pair-job %s K\n"
              "then:           scanreg-cli register %s --collect %s\n",
              jobs, result->pairs_matched, result->pairs_possible, d.c_str(), d.c_str(), jobs - 1, jobs - 1, d.c_str(),
              jobs - 1, d.c_str(), project.file.string().c_str(), d.c_str());
  return 0;
}

Status CollectPairJobs(const io::Project& project, const fs::path& dir, pipeline::RegisterOptions* options,
                       std::map<std::pair<int, int>, pipeline::PairResult>* results) {
  Expected<pipeline::PairJobPlan> plan = pipeline::ReadPairJobPlan(dir);
  if (!plan) return plan.error();
  if (Status s = pipeline::CheckSameSettings(*plan, project.settings, ScanNames(project)); !s)
    return MakeError(s.error().code, "register --collect " + dir.string() + ": " + s.error().message);
  std::vector<std::string> problems;
  *results = pipeline::ReadPairJobResults(dir, *plan, &problems);
  for (const std::string& p : problems) std::fprintf(stderr, "register --collect: %s; registered here instead\n", p.c_str());
  std::fprintf(stderr, "register --collect: %zu of %zu pair jobs collected\n", plan->pairs.size() - problems.size(),
               plan->pairs.size());
  *options = pipeline::WithPlanLengths(*options, *plan);
  return Status::Ok();
}

int RunPairJob(const std::vector<std::string>& argv) {
  int code = 0;
  auto args = ParseOrHelp(
      "pair-job",
      "DIR [K]   registers the scans of pair job K of the plan in DIR to each other (both ways) and writes "
      "DIR/results/pair-K.json; K defaults to $SLURM_ARRAY_TASK_ID (plan with register PROJECT --plan DIR)",
      argv, {}, &code);
  if (!args) return code;
  const auto& pos = args->positional();
  if (pos.empty() || pos.size() > 2)
    return Fail(MakeError(ErrorCode::kInvalidArgument, "pair-job: give the plan's folder and the job number"));
  std::string k_text = pos.size() == 2 ? pos[1] : "";
  if (k_text.empty() && std::getenv("SLURM_ARRAY_TASK_ID")) k_text = std::getenv("SLURM_ARRAY_TASK_ID");
  const fs::path dir = pos[0];
  Expected<pipeline::PairJobPlan> plan = pipeline::ReadPairJobPlan(dir);
  if (!plan) return Fail(plan.error());
  char* end = nullptr;
  const long k = k_text.empty() ? -1 : std::strtol(k_text.c_str(), &end, 10);
  if (k_text.empty() || *end != '\0' || k < 0 || k >= static_cast<long>(plan->pairs.size())) {
    return Fail(MakeError(ErrorCode::kInvalidArgument,
                          "pair-job: job number '" + k_text + "' is not one of 0 .. " +
                              std::to_string(plan->pairs.size() - 1) + " (give K, or set SLURM_ARRAY_TASK_ID)"));
  }
  auto project = io::LoadProject(plan->project);
  if (!project) return Fail(project.error());
  if (Status s = pipeline::CheckSameSettings(*plan, project->settings, ScanNames(*project)); !s)
    return Fail(MakeError(s.error().code, "pair-job: " + s.error().message));
  auto options = pipeline::ProjectRegisterOptions(*project);
  if (!options) return Fail(options.error());
  options->feature_cache_dir = pipeline::ProjectCacheDir(*project);
  const auto [a, b] = plan->pairs[k];
  NullProgress quiet;
  CancelToken& cancel = InterruptToken();
  auto scans = pipeline::LoadProjectScans(*project, quiet, cancel, {a, b});
  if (!scans) return Fail(scans.error());
  auto result = pipeline::RunPairJob((*scans)[0], (*scans)[1], pipeline::WithPlanLengths(*options, *plan), cancel);
  if (!result) return Fail(result.error());
  if (Status s = pipeline::WritePairJobResult(dir, *plan, static_cast<int>(k), *result); !s) return Fail(s.error());
  std::printf("job %ld: %s -> %s %s, %s -> %s %s\n", k, (*result)[0].link.child.c_str(),
              (*result)[0].link.parent.c_str(), io::LinkStatusName((*result)[0].link.status),
              (*result)[1].link.child.c_str(), (*result)[1].link.parent.c_str(),
              io::LinkStatusName((*result)[1].link.status));
  return 0;
}

}  // namespace scanreg::cli
