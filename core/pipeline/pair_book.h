// The pair registrations of one run of the registration driver (registration_driver.h): each
// ordered pair is registered at most once, the user's kept links are taken as they are, and pairs
// wanted next are registered ahead, concurrently. Also the run's excluded (parent, child) pairs:
// the user's rejections and every link failed since.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/pipeline/register_pair.h"
#include "core/pipeline/register_project.h"

namespace scanreg::pipeline {

struct LinkSource;

class PairBook {
 public:
  PairBook(const std::vector<Scan>& scans, const ScanOrderChoices& choices, const LinkSource& source,
           ProgressSink& progress, const CancelToken& cancel);

  // Registers the wanted pairs not registered yet concurrently (issue 13, item 4); they wait until
  // Link asks for them, so the result is the same whatever the thread count.
  void RegisterAhead(const std::vector<std::pair<int, int>>& wanted);
  // The pair's result: registered now, taken from ahead, or the user's kept link (logged once).
  PairResult& Link(int parent, int child);
  // Marks a registered pair failed with the reason and excludes it.
  void Fail(int parent, int child, const std::string& reason);
  void Exclude(int parent, int child) { excluded_.emplace_back(parent, child); }

  bool Has(int parent, int child) const { return done_.count({parent, child}) > 0; }
  PairResult& At(int parent, int child) { return done_.at({parent, child}); }
  const PairResult& At(int parent, int child) const { return done_.at({parent, child}); }
  const PairResult* Find(int parent, int child) const;
  bool Excluded(int parent, int child) const;
  const std::vector<std::pair<int, int>>& excluded() const { return excluded_; }
  const std::map<std::pair<int, int>, PairResult>& done() const { return done_; }

 private:
  double Fraction() const;

  const std::vector<Scan>& scans_;
  const ScanOrderChoices& choices_;
  const LinkSource& source_;
  ProgressSink& progress_;
  const CancelToken& cancel_;
  std::vector<std::pair<int, int>> excluded_;
  std::map<std::pair<int, int>, PairResult> done_, ahead_;
};

}  // namespace scanreg::pipeline
