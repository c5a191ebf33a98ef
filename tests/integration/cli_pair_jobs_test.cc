// register --plan / pair-job / register --collect (issue 13, item 6) end to end with the real
// scanreg-cli: the jobs run as parallel local processes, and the collected project is the one a
// single process registers.
#include <cstdlib>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/geometry/transform.h"
#include "core/io/project.h"
#include "tests/integration/cli_run.h"
#include "tests/integration/same_registration.h"
#include "tests/support/test_paths.h"

namespace scanreg {
namespace {

namespace fs = std::filesystem;
using test::Quote;
using test::RunCli;
using test::RunResult;
using test::ExpectSameRegistration;
using test::Street;

int PlannedJobs(const fs::path& plan_dir) {
  std::ifstream in(plan_dir / "plan.json");
  return nlohmann::json::parse(in).at("jobs").get<int>();
}

// Runs jobs 0 .. jobs-1 two at a time, as two local worker processes would.
int RunJobsInParallel(const fs::path& plan_dir, int jobs) {
  const std::string cmd = "seq 0 " + std::to_string(jobs - 1) + " | xargs -P 2 -I K " + std::string(SCANREG_CLI) +
                          " pair-job " + Quote(plan_dir) + " K > /dev/null";
  return std::system(cmd.c_str());
}

TEST(PairJobs, PlanRunCollectGivesTheSingleProcessRegistration) {
  test::TempDir dir;
  const fs::path single = Street(dir, "single"), spread = Street(dir, "spread");
  const RunResult one = RunCli("register " + Quote(single) + " --candidates 3");
  ASSERT_EQ(one.status, 0) << one.output;

  const fs::path jobs_dir = dir / "jobs";
  const RunResult plan = RunCli("register " + Quote(spread) + " --candidates 3 --plan " + Quote(jobs_dir));
  ASSERT_EQ(plan.status, 0) << plan.output;
  EXPECT_NE(plan.output.find("pair-job"), std::string::npos) << "the plan says how to run the jobs:\n" << plan.output;
  const int jobs = PlannedJobs(jobs_dir);
  EXPECT_GE(jobs, 5) << "at least the neighbours along the street";
  EXPECT_LT(jobs, 15) << "candidate pairs, not all 15";
  ASSERT_EQ(RunJobsInParallel(jobs_dir, jobs), 0);
  for (int k = 0; k < jobs; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "pair-%05d.json", k);
    EXPECT_TRUE(fs::exists(jobs_dir / "results" / name)) << name;
  }
  const RunResult collected = RunCli("register " + Quote(spread) + " --collect " + Quote(jobs_dir));
  ASSERT_EQ(collected.status, 0) << collected.output;
  EXPECT_NE(collected.output.find(std::to_string(jobs) + " of " + std::to_string(jobs) + " pair jobs collected"),
            std::string::npos)
      << collected.output;
  EXPECT_NE(collected.output.find("pair registrations from the pair jobs:"), std::string::npos) << collected.output;

  ExpectSameRegistration(single, spread);
}

TEST(PairJobs, BadJobsAndChangedSettingsAreClearErrors) {
  test::TempDir dir;
  const fs::path project = Street(dir, "p");
  const fs::path jobs_dir = dir / "jobs";
  const RunResult plan = RunCli("register " + Quote(project) + " --candidates 3 --plan " + Quote(jobs_dir));
  ASSERT_EQ(plan.status, 0) << plan.output;
  const int jobs = PlannedJobs(jobs_dir);

  RunResult r = RunCli("pair-job " + Quote(jobs_dir) + " " + std::to_string(jobs));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("is not one of 0 .. " + std::to_string(jobs - 1)), std::string::npos) << r.output;
  r = RunCli("pair-job " + Quote(dir / "nowhere") + " 0");
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("register --plan"), std::string::npos) << r.output;

  // Job 0 runs; job 1's result is damaged; the rest never ran: the collect says so and registers
  // those pairs itself.
  r = RunCli("pair-job " + Quote(jobs_dir) + " 0");
  ASSERT_EQ(r.status, 0) << r.output;
  std::ofstream(jobs_dir / "results" / "pair-00001.json") << "{\"plan\": \"";
  r = RunCli("register " + Quote(project) + " --collect " + Quote(jobs_dir));
  EXPECT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("1 of " + std::to_string(jobs) + " pair jobs collected"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not valid JSON"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no result (not run, or it failed)"), std::string::npos) << r.output;

  // Settings changed since the plan: the jobs' results would not be this registration's.
  r = RunCli("register " + Quote(project) + " --ratio 0.7 --collect " + Quote(jobs_dir));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("settings changed since the plan"), std::string::npos) << r.output;
  r = RunCli("register " + Quote(project) + " --plan " + Quote(jobs_dir) + " --collect " + Quote(jobs_dir));
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("not both"), std::string::npos) << r.output;
}

// The Slurm recipe (packaging/slurm/pair-jobs.sbatch) on whatever cluster answers here: the single
// node of packaging/slurm/single-node.sh, which CI starts (and sets SCANREG_REQUIRE_SLURM, so that
// there a missing cluster fails the test instead of skipping it).
TEST(PairJobs, ASlurmArrayGivesTheSingleProcessRegistration) {
  if (std::system("sinfo -h > /dev/null 2>&1") != 0) {
    if (std::getenv("SCANREG_REQUIRE_SLURM")) FAIL() << "SCANREG_REQUIRE_SLURM is set but no Slurm cluster answers (sinfo)";
    GTEST_SKIP() << "no Slurm cluster answers (sinfo): not tested (packaging/slurm/single-node.sh starts one)";
  }
  test::TempDir dir;
  const fs::path single = Street(dir, "single"), spread = Street(dir, "spread");
  ASSERT_EQ(RunCli("register " + Quote(single) + " --candidates 3").status, 0);
  const fs::path jobs_dir = dir / "jobs";
  ASSERT_EQ(RunCli("register " + Quote(spread) + " --candidates 3 --plan " + Quote(jobs_dir)).status, 0);
  const int jobs = PlannedJobs(jobs_dir);
  const std::string submit = "cd " + Quote(dir.path()) + " && SCANREG_CLI=" + std::string(SCANREG_CLI) +
                             " sbatch --wait --array=0-" + std::to_string(jobs - 1) + " " +
                             std::string(SCANREG_SLURM_SCRIPT) + " " + Quote(jobs_dir) + " > /dev/null";
  ASSERT_EQ(std::system(submit.c_str()), 0) << submit;
  const RunResult collected = RunCli("register " + Quote(spread) + " --collect " + Quote(jobs_dir));
  ASSERT_EQ(collected.status, 0) << collected.output;
  EXPECT_NE(collected.output.find(std::to_string(jobs) + " of " + std::to_string(jobs) + " pair jobs collected"),
            std::string::npos)
      << collected.output;
  ExpectSameRegistration(single, spread);
}

}  // namespace
}  // namespace scanreg
