// Shared helpers of the subcommands: help text, error printing, terminal progress.
#pragma once

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "app/cli_args.h"
#include "core/common/expected.h"
#include "core/common/progress.h"

namespace scanreg::cli {

// Prints "scanreg-cli: <message>" on stderr and returns the exit status for the error's kind.
int Fail(const Error& error);

// Parses args; on --help prints usage and sets *exit_code = 0; on error prints it, *exit_code = 2.
// Returns the parsed args when the command should run.
std::optional<Args> ParseOrHelp(const std::string& command, const std::string& usage,
                                const std::vector<std::string>& argv, std::vector<OptionSpec> specs, int* exit_code);

// The command's cancel token: Ctrl-C (SIGINT) or SIGTERM cancels it, so a long job stops at its next
// check, removes its temporary files and exits with 130 having written nothing; a second signal
// ends the process at once.
CancelToken& InterruptToken();

// Progress on stderr: one line per stage and every 10 %, only when stderr is a terminal or
// SCANREG_PROGRESS=1.
class TerminalProgress final : public ProgressSink {
 public:
  TerminalProgress();
  void Report(double fraction, const std::string& stage) override;

 private:
  bool enabled_;
  std::string stage_;
  int last_decile_ = -1;
};

}  // namespace scanreg::cli
