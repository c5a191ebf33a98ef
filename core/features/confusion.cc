#include "core/features/confusion.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

namespace scanreg {
namespace {

std::size_t PairSlot(int n, int i, int j) {
  return static_cast<std::size_t>(i) * (n - 1) + (j < i ? j : j - 1);
}

// Reports progress at most ~200 times over `total` steps, from any thread.
class StepProgress {
 public:
  StepProgress(ProgressSink& sink, long total, std::string stage)
      : sink_(sink), total_(std::max(total, 1L)), stride_(std::max(1L, total_ / 200)), stage_(std::move(stage)) {}
  void Step() {
    const long done = ++done_;
    if (done % stride_ == 0 || done == total_) sink_.Report(static_cast<double>(done) / total_, stage_);
  }

 private:
  ProgressSink& sink_;
  long total_;
  long stride_;
  std::string stage_;
  std::atomic<long> done_{0};
};

}  // namespace

const PairMatches* MatchTable::Find(int i, int j) const {
  const int n = static_cast<int>(confusion.rows());
  if (i == j || i < 0 || j < 0 || i >= n || j >= n) return nullptr;
  const std::size_t slot = PairSlot(n, i, j);
  return slot < pairs.size() ? &pairs[slot] : nullptr;
}

Expected<MatchTable> MatchAllPairs(const std::vector<ScanFeatures>& scans, const MatchOptions& options,
                                   ProgressSink& progress, const CancelToken& cancel) {
  std::vector<std::pair<int, int>> all;
  for (int i = 0; i < static_cast<int>(scans.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(scans.size()); ++j) all.emplace_back(i, j);
  return MatchPairs(scans, all, options, progress, cancel);
}

Expected<MatchTable> MatchPairs(const std::vector<ScanFeatures>& scans, const std::vector<std::pair<int, int>>& pairs,
                                const MatchOptions& options, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const int n = static_cast<int>(scans.size());
  for (int i = 0; i < n; ++i)
    if (scans[i].descriptors.size() != scans[i].keypoints.size() * kSiftDescriptorSize)
      return MakeError(ErrorCode::kInvalidArgument, "matching: the features of scan " + std::to_string(i + 1) +
                                                        " have " + std::to_string(scans[i].descriptors.size()) +
                                                        " descriptor values for " +
                                                        std::to_string(scans[i].keypoints.size()) +
                                                        " keypoints; re-run feature detection");
  MatchTable table;
  table.confusion = Eigen::MatrixXi::Constant(n, n, kSkippedPair);
  for (int i = 0; i < n; ++i) table.confusion(i, i) = scans[i].size();
  if (n < 2) return table;
  table.pairs.resize(static_cast<std::size_t>(n) * (n - 1));

  // Unordered pairs {i < j}, each once: one task matches both directions (for kExact from one product).
  std::vector<std::pair<int, int>> tasks;
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || a >= n || b >= n || a == b)
      return MakeError(ErrorCode::kInvalidArgument, "matching: pair (" + std::to_string(a) + ", " +
                                                        std::to_string(b) + ") is not a pair of the " +
                                                        std::to_string(n) + " scans");
    tasks.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(tasks.begin(), tasks.end());
  tasks.erase(std::unique(tasks.begin(), tasks.end()), tasks.end());
  const long num_tasks = static_cast<long>(tasks.size());
  StepProgress steps(progress, n + num_tasks, "Matching features");
  std::atomic<bool> cancelled{false};
  std::mutex error_mutex;
  std::string error;  // first failure (an exception from OpenCV, e.g. out of memory)
  auto record_error = [&](const std::string& what) {
    std::lock_guard<std::mutex> lock(error_mutex);
    if (error.empty()) error = what;
    cancelled = true;
  };

  // One index per scan (each index depends only on its scan and the seed: thread-count independent).
  std::vector<std::unique_ptr<MatchIndex>> indices(n);
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < n; ++i) {
    if (cancelled || cancel.IsCancelled()) {
      cancelled = true;
      continue;
    }
    try {
      indices[i] = std::make_unique<MatchIndex>(scans[i], options);
    } catch (const std::exception& e) {
      record_error("building the search index of scan " + std::to_string(i + 1) + " failed: " + e.what());
    }
    steps.Step();
  }

#pragma omp parallel for schedule(dynamic, 1)
  for (long t = 0; t < num_tasks; ++t) {
    if (cancelled || cancel.IsCancelled()) {
      cancelled = true;
      continue;
    }
    const auto [i, j] = tasks[static_cast<std::size_t>(t)];
    PairMatches& ij = table.pairs[PairSlot(n, i, j)];
    PairMatches& ji = table.pairs[PairSlot(n, j, i)];
    ij.query_scan = ji.train_scan = i;
    ij.train_scan = ji.query_scan = j;
    try {
      TwoWayMatches both = MatchRatioBothWays(*indices[i], *indices[j], options);
      ij.matches = std::move(both.a_in_b);
      ji.matches = std::move(both.b_in_a);
    } catch (const std::exception& e) {
      record_error("matching scans " + std::to_string(i + 1) + " and " + std::to_string(j + 1) + " failed: " +
                   e.what());
    }
    steps.Step();
  }
  if (!error.empty()) return MakeError(ErrorCode::kFailed, error);
  if (cancelled) return MakeError(ErrorCode::kCancelled, "feature matching was cancelled");
  for (const PairMatches& pm : table.pairs)
    if (pm.query_scan >= 0) table.confusion(pm.query_scan, pm.train_scan) = static_cast<int>(pm.matches.size());
  return table;
}

Expected<Eigen::MatrixXi> ConfusionMatrix(const std::vector<ScanFeatures>& scans, const MatchOptions& options,
                                          ProgressSink& progress, const CancelToken& cancel) {
  Expected<MatchTable> table = MatchAllPairs(scans, options, progress, cancel);
  if (!table) return table.error();
  return std::move(table->confusion);
}

}  // namespace scanreg
