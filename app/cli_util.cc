#include "app/cli_util.h"

#include <unistd.h>

#include <csignal>
#include <cstdlib>

#include "core/io/text_parse.h"

namespace scanreg::cli {

namespace {

CancelToken interrupt_token;

extern "C" void OnInterrupt(int signal) {
  interrupt_token.Cancel();            // a lock-free atomic store: safe in a handler
  std::signal(signal, SIG_DFL);        // a second one ends the process
}

}  // namespace

CancelToken& InterruptToken() {
  static const bool installed = [] {
    std::signal(SIGINT, OnInterrupt);
    std::signal(SIGTERM, OnInterrupt);
    return true;
  }();
  (void)installed;
  return interrupt_token;
}

int Fail(const Error& error) {
  std::fprintf(stderr, "scanreg-cli: %s\n", EscapeControlBytes(error.message).c_str());
  switch (error.code) {
    case ErrorCode::kInvalidArgument:
      return 2;
    case ErrorCode::kCancelled:
      return 130;
    default:
      return 1;
  }
}

std::optional<Args> ParseOrHelp(const std::string& command, const std::string& usage,
                                const std::vector<std::string>& argv, std::vector<OptionSpec> specs, int* exit_code) {
  specs.push_back({"help", false, false, "       show this help"});
  Expected<Args> args = Args::Parse(command, argv, specs);
  if (!args) {
    *exit_code = Fail(args.error());
    return std::nullopt;
  }
  if (args->Has("help")) {
    std::printf("usage: scanreg-cli %s %s\n\noptions:\n", command.c_str(), usage.c_str());
    for (const OptionSpec& s : specs) std::printf("  --%-16s %s\n", s.name.c_str(), s.help.c_str());
    *exit_code = 0;
    return std::nullopt;
  }
  return std::move(*args);
}

TerminalProgress::TerminalProgress() {
  const char* env = std::getenv("SCANREG_PROGRESS");
  enabled_ = (env && std::string(env) == "1") || ::isatty(STDERR_FILENO);
}

void TerminalProgress::Report(double fraction, const std::string& stage) {
  if (!enabled_) return;
  const int decile = static_cast<int>(fraction * 10.0 + 1e-9);
  if (stage == stage_ && decile == last_decile_) return;
  stage_ = stage;
  last_decile_ = decile;
  std::fprintf(stderr, "  %3d%%  %s\n", decile * 10, stage.c_str());
}

}  // namespace scanreg::cli
