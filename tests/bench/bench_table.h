// The benchmark's output: one table of figures, printed at the end. Sections add rows.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace scanreg::bench {

// printf-style formatting of up to three numbers, for notes.
inline std::string Fmt(const char* fmt, double a, double b = 0, double c = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c);
  return buf;
}

struct Row {
  std::string section;  // e.g. "io", "simulate"
  std::string what;     // e.g. "PTX read 2.25 M points"
  double value = 0.0;
  std::string unit;     // e.g. "M points/s"
  std::string note;     // baseline, data size, ...
};

class Table {
 public:
  void Add(Row row) { rows_.push_back(std::move(row)); }
  void Print() const;

 private:
  std::vector<Row> rows_;
};

// Wall-clock seconds of a callable.
template <typename F>
double Seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Peak resident set size of this process so far, in MiB (from /proc/self/status VmHWM).
double PeakMemoryMiB();
// Starts the peak over (Linux: /proc/self/clear_refs), so the next PeakMemoryMiB is of what follows.
void ResetPeakMemory();

// Sections. Each takes the table and a "quick" flag (smaller sizes for a smoke run).
void RunIoBench(Table& table, bool quick);
void RunSimulateBench(Table& table, bool quick);
void RunRegisterBench(Table& table, bool quick);
void RunMergeBench(Table& table, bool quick);
void RunExportBench(Table& table, bool quick);
void RunEmBench(Table& table, bool quick);
void RunGlobalBench(Table& table, bool quick);
void RunGeometricBench(Table& table, bool quick);
void RunHardBench(Table& table, bool quick);
void RunGeorefBench(Table& table, bool quick);
void RunCityBench(Table& table, bool quick);
void RunTrustBench(Table& table, bool quick);  // bench_trust.cc
void RunInteriorsBench(Table& table, bool quick);  // bench_interiors.cc
void RunCombinedBench(Table& table, bool quick);   // bench_combined.cc
void RunPairsBench(Table& table, bool quick);      // bench_pairs.cc
void RunBigScansBench(Table& table, bool quick);  // bench_city.cc
void RunListsBench(Table& table, bool quick);     // bench_lists.cc

}  // namespace scanreg::bench
