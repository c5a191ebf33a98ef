#include "core/pipeline/pair_book.h"

#include <algorithm>

#include "core/common/log.h"
#include "core/pipeline/registration_driver.h"

namespace scanreg::pipeline {

PairBook::PairBook(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
                   ProgressSink& progress, const CancelToken& cancel)
    : scans_(scans), choices_(choices), source_(source), progress_(progress), cancel_(cancel), excluded_(choices.excluded) {}

double PairBook::Fraction() const {
  const int n = static_cast<int>(scans_.size());
  return std::min(1.0, double(done_.size()) / (2.0 * std::max(1, n - 1)));
}

void PairBook::RegisterAhead(const std::vector<std::pair<int, int>>& wanted) {
  std::vector<std::pair<int, int>> todo;
  for (const auto& e : wanted)
    if (!done_.count(e) && !ahead_.count(e) && !choices_.kept.count(e) &&
        std::find(todo.begin(), todo.end(), e) == todo.end())
      todo.push_back(e);
  if (todo.size() < 2 || cancel_.IsCancelled()) return;  // nothing to share between threads
  progress_.Report(Fraction(), std::string(source_.verb) + " " + std::to_string(todo.size()) + " pairs");
  std::vector<PairResult> results(todo.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(todo.size()); ++k)
    if (!cancel_.IsCancelled()) results[k] = source_.register_pair(todo[k].first, todo[k].second);
  if (cancel_.IsCancelled()) return;
  for (std::size_t k = 0; k < todo.size(); ++k) ahead_.emplace(todo[k], std::move(results[k]));
}

PairResult& PairBook::Link(int parent, int child) {
  auto it = done_.find({parent, child});
  if (it != done_.end()) return it->second;
  progress_.Report(Fraction(), std::string(source_.verb) + " " + scans_[child].name + " to " + scans_[parent].name);
  const auto kept = choices_.kept.find({parent, child});
  PairResult computed;
  if (kept != choices_.kept.end()) {
    computed.link = kept->second;
  } else if (auto a = ahead_.find({parent, child}); a != ahead_.end()) {
    computed = std::move(a->second);
    ahead_.erase(a);
  } else {
    computed = source_.register_pair(parent, child);
  }
  PairResult& r = done_.emplace(std::make_pair(parent, child), std::move(computed)).first->second;
  if (kept != choices_.kept.end()) LogInfo(scans_[child].name + " keeps its link to " + scans_[parent].name + " (the user's)");
  LogInfo(scans_[child].name + " -> " + scans_[parent].name + ": " + io::LinkStatusName(r.link.status) +
          (r.link.reason.empty() ? "" : " (" + r.link.reason + ")"));
  return r;
}

void PairBook::Fail(int parent, int child, const std::string& reason) {
  PairResult& r = done_.at({parent, child});
  r.link.status = io::LinkStatus::kFailed;
  r.link.reason = reason;
  r.unconfirmed = false;
  excluded_.emplace_back(parent, child);
}

const PairResult* PairBook::Find(int parent, int child) const {
  const auto it = done_.find({parent, child});
  return it == done_.end() ? nullptr : &it->second;
}

bool PairBook::Excluded(int parent, int child) const {
  return std::find(excluded_.begin(), excluded_.end(), std::make_pair(parent, child)) != excluded_.end();
}

}  // namespace scanreg::pipeline
