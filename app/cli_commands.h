// scanreg-cli subcommands. Each returns the process exit status; errors go to stderr as one line.
#pragma once

#include <string>

#include "core/io/project.h"
#include "core/pipeline/register_options.h"
#include <vector>

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
int RunExportPoses(const std::vector<std::string>& args);
int RunConvert(const std::vector<std::string>& args);
int RunRegister(const std::vector<std::string>& args);
int RunMerge(const std::vector<std::string>& args);
int RunReport(const std::vector<std::string>& args);
int RunExportClouds(const std::vector<std::string>& args);

const std::vector<Command>& Commands();

// Registers the project's scans, saves the project and prints the evidence (text or JSON).
// Returns 0 when every scan is registered, 3 when some are not, another code on errors.
int RegisterAndReport(io::Project& project, pipeline::RegisterOptions options, bool json);

}  // namespace scanreg::cli
