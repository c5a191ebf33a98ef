// scanreg-cli: batch registration of terrestrial laser scans. Thin: dispatches to subcommands.
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "app/cli_commands.h"
#include "core/common/allocator.h"

namespace {

void PrintUsage(std::FILE* out) {
  std::fprintf(out,
               "scanreg-cli %s — registration of terrestrial laser scans\n\n"
               "usage: scanreg-cli COMMAND [ARGS...]   (scanreg-cli COMMAND --help for details)\n\ncommands:\n",
               SCANREG_VERSION);
  for (const auto& c : scanreg::cli::Commands()) std::fprintf(out, "  %-14s %s\n", c.name, c.summary);
}

}  // namespace

int main(int argc, char** argv) {
  scanreg::ReuseFreedMemory();
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintUsage(stdout);
    return argc < 2 ? 2 : 0;
  }
  if (std::strcmp(argv[1], "--version") == 0) {
    std::printf("scanreg-cli %s\n", SCANREG_VERSION);
    return 0;
  }
  const std::vector<std::string> args(argv + 2, argv + argc);
  for (const auto& c : scanreg::cli::Commands())
    if (std::strcmp(argv[1], c.name) == 0) return c.run(args);
  std::fprintf(stderr, "scanreg-cli: unknown command '%s'; run 'scanreg-cli --help' for the list\n", argv[1]);
  return 2;
}
