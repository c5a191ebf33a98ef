// register --memory-budget (issue 13, item 1) end to end with the real scanreg-cli: a budget
// smaller than one scan reads the scans again as pairs need them, and registers exactly as a run
// that holds every scan.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "tests/integration/cli_run.h"
#include "tests/integration/same_registration.h"

namespace scanreg {
namespace {

namespace fs = std::filesystem;
using test::Quote;
using test::RunCli;
using test::RunResult;

nlohmann::json Memory(const RunResult& r) {
  const auto start = r.output.find("{\n");
  if (start == std::string::npos) return nlohmann::json();
  return nlohmann::json::parse(r.output.substr(start), nullptr, false).value("memory", nlohmann::json());
}

TEST(MemoryBudget, ABudgetSmallerThanAScanGivesTheSameRegistration) {
  test::TempDir dir;
  const fs::path held = test::Street(dir, "held"), read_again = test::Street(dir, "read-again");
  const RunResult all = RunCli("register " + Quote(held) + " --candidates 3 --json");
  ASSERT_EQ(all.status, 0) << all.output;
  const nlohmann::json m_all = Memory(all);
  ASSERT_TRUE(m_all.is_object()) << all.output;
  EXPECT_EQ(m_all.at("scan_reads").get<int>(), 6) << "a budget that holds every scan reads each once";
  const int builds_all = m_all.at("surface_builds").get<int>();
  EXPECT_GE(builds_all, 1);
  EXPECT_LE(builds_all, 6) << "a budget that holds every surface builds each at most once";

  // A 600 x 150 scan holds 1.5 MB; 1M keeps only the scans in use.
  const RunResult small = RunCli("register " + Quote(read_again) + " --candidates 3 --memory-budget 1M --json");
  ASSERT_EQ(small.status, 0) << small.output;
  const nlohmann::json m_small = Memory(small);
  ASSERT_TRUE(m_small.is_object()) << small.output;
  EXPECT_GT(m_small.at("scan_reads").get<int>(), 12) << "read for the scale, the features and the pairs' free-space tests";
  EXPECT_LT(m_small.at("peak_bytes").get<double>(), 0.5 * m_all.at("peak_bytes").get<double>());
  EXPECT_GT(m_small.at("surface_builds").get<int>(), builds_all) << "surfaces dropped under the budget are built again";
  test::ExpectSameRegistration(held, read_again);
}

TEST(MemoryBudget, ANonsenseBudgetIsAClearError) {
  test::TempDir dir;
  const fs::path project = test::Street(dir, "p");
  for (const char* bad : {"lots", "10K", "-2G"}) {
    const RunResult r = RunCli("register " + Quote(project) + " --memory-budget " + bad);
    EXPECT_NE(r.status, 0) << bad;
    EXPECT_NE(r.output.find("--memory-budget"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("e.g. 6G"), std::string::npos) << r.output;
  }
}

}  // namespace
}  // namespace scanreg
