// scanreg-cli subcommands. Each returns the process exit status; errors go to stderr as one line.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/io/project.h"
#include "core/pipeline/pair_jobs.h"
#include "core/pipeline/register_options.h"

namespace scanreg::cli {

struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>& args);
};

int RunSimulate(const std::vector<std::string>& args);
int RunDemo(const std::vector<std::string>& args);
int RunNew(const std::vector<std::string>& args);
int RunInfo(const std::vector<std::string>& args);
int RunLink(const std::vector<std::string>& args);
int RunExportPoses(const std::vector<std::string>& args);
int RunConvert(const std::vector<std::string>& args);
int RunRegister(const std::vector<std::string>& args);
int RunMerge(const std::vector<std::string>& args);
int RunReport(const std::vector<std::string>& args);
int RunExportClouds(const std::vector<std::string>& args);

const std::vector<Command>& Commands();

// Registers the project's scans, saves the project and prints the evidence (text or JSON).
// Returns 0 when every scan is registered, 3 when some are not, another code on errors.
// exchange: the pair registrations of pair jobs (register --collect). The scans are read through a
// store (core/pipeline/scan_store.h) holding at most memory_budget bytes of them (0: the default).
int RegisterAndReport(io::Project& project, pipeline::RegisterOptions options, bool json,
                      const pipeline::PairExchange* exchange = nullptr, std::size_t memory_budget = 0);

// Pair jobs (cli_pair_jobs.cc, core/pipeline/pair_jobs.h): register --plan DIR writes the plan;
// register --collect DIR reads the plan's results into *results and sets the plan's lengths.
int PlanPairJobs(io::Project& project, pipeline::RegisterOptions options, const std::filesystem::path& dir,
                 std::size_t memory_budget = 0);
Status CollectPairJobs(const io::Project& project, const std::filesystem::path& dir, pipeline::RegisterOptions* options,
                       std::map<std::pair<int, int>, pipeline::PairResult>* results);
int RunPairJob(const std::vector<std::string>& args);

}  // namespace scanreg::cli
