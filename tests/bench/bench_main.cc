// scanreg-bench: prints a table of speed and memory figures. Not a test: nothing here asserts a
// time. `--quick` runs reduced sizes.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/common/allocator.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/pcl_baseline.h"

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

void ResetPeakMemory() { std::ofstream("/proc/self/clear_refs") << "5"; }

}  // namespace scanreg::bench

int main(int argc, char** argv) {
  scanreg::ReuseFreedMemory();
  // The K-4PCS baseline's child process (pcl_baseline.h).
  if (argc == 6 && std::strcmp(argv[1], "--kfpcs-child") == 0)
    return scanreg::bench::RunKfpcsChild(argv[2], argv[3], std::atof(argv[4]), std::atoi(argv[5]));
  using Section = void (*)(scanreg::bench::Table&, bool);
  const std::vector<std::pair<std::string, Section>> sections = {
      {"simulate", scanreg::bench::RunSimulateBench}, {"io", scanreg::bench::RunIoBench},
      {"register", scanreg::bench::RunRegisterBench}, {"merge", scanreg::bench::RunMergeBench},
      {"export", scanreg::bench::RunExportBench},
      {"em", scanreg::bench::RunEmBench}, {"global", scanreg::bench::RunGlobalBench},
      {"geometric", scanreg::bench::RunGeometricBench}, {"hard", scanreg::bench::RunHardBench},
      {"georef", scanreg::bench::RunGeorefBench}, {"city", scanreg::bench::RunCityBench},
      {"big", scanreg::bench::RunBigScansBench}, {"trust", scanreg::bench::RunTrustBench},
      {"interiors", scanreg::bench::RunInteriorsBench}, {"combined", scanreg::bench::RunCombinedBench},
      {"pairs", scanreg::bench::RunPairsBench},
      {"lists", scanreg::bench::RunListsBench}};
  bool quick = false;
  std::vector<std::string> chosen;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      quick = true;
    } else if (std::strcmp(argv[i], "--section") == 0 && i + 1 < argc) {
      chosen.emplace_back(argv[++i]);
    } else {
      std::fprintf(stderr, "usage: scanreg-bench [--quick] [--section simulate|io|register|merge|export|em|global|geometric|hard|georef|city|big|trust|interiors|combined|pairs|lists ...]\n");
      return 2;
    }
  }
  for (const std::string& c : chosen) {
    bool known = false;
    for (const auto& s : sections) known |= s.first == c;
    if (!known) {
      std::fprintf(stderr, "scanreg-bench: unknown section '%s'\n", c.c_str());
      return 2;
    }
  }
  scanreg::bench::Table table;
  for (const auto& [name, run] : sections)
    if (chosen.empty() || std::find(chosen.begin(), chosen.end(), name) != chosen.end()) run(table, quick);
  table.Add({"process", "peak resident memory", scanreg::bench::PeakMemoryMiB(), "MiB", ""});
  table.Print();
  return 0;
}
