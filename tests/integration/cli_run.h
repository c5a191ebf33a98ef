// Running the real scanreg-cli binary (SCANREG_CLI, set by CMake) as a user would, for the
// integration tests.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/io/io_test_util.h"

namespace scanreg::test {

struct RunResult {
  int status = -1;
  std::string output;  // stdout and stderr
};

// A shell command line, its stderr with its stdout.
inline RunResult RunCommand(const std::string& command_line) {
  RunResult r;
  const std::string cmd = command_line + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int st = pclose(pipe);
  r.status = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

inline RunResult RunCli(const std::string& args) { return RunCommand(std::string(SCANREG_CLI) + " " + args); }

inline std::string Quote(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

}  // namespace scanreg::test
