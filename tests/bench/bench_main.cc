// scanreg-bench: prints a table of speed and memory figures. Not a test: nothing here asserts a
// time. `--quick` runs reduced sizes.
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "tests/bench/bench_table.h"

namespace scanreg::bench {

void Table::Print() const {
  std::printf("\n%-10s %-52s %14s  %-12s %s\n", "section", "measure", "value", "unit", "note");
  std::printf("%s\n", std::string(120, '-').c_str());
  for (const Row& r : rows_)
    std::printf("%-10s %-52s %14.3f  %-12s %s\n", r.section.c_str(), r.what.c_str(), r.value, r.unit.c_str(),
                r.note.c_str());
}

double PeakMemoryMiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

}  // namespace scanreg::bench

int main(int argc, char** argv) {
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: scanreg-bench [--quick]\n");
      return 2;
    }
  }
  scanreg::bench::Table table;
  scanreg::bench::RunSimulateBench(table, quick);
  scanreg::bench::RunIoBench(table, quick);
  scanreg::bench::RunRegisterBench(table, quick);
  scanreg::bench::RunMergeBench(table, quick);
  scanreg::bench::RunEmBench(table, quick);
  table.Add({"process", "peak resident memory", scanreg::bench::PeakMemoryMiB(), "MiB", ""});
  table.Print();
  return 0;
}
