// Progress reporting and cancellation for long jobs (STYLE.md, convention 4).
#pragma once

#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <utility>

namespace scanreg {

// Receives progress of a long job. Implementations must be thread-safe: parallel loops report
// from worker threads.
class ProgressSink {
 public:
  virtual ~ProgressSink() = default;
  // fraction in [0, 1] of the current stage; stage is a short human-readable label.
  virtual void Report(double fraction, const std::string& stage) = 0;
};

class NullProgress final : public ProgressSink {
 public:
  void Report(double, const std::string&) override {}
};

// Forwards to a callback, serialised by a mutex.
class CallbackProgress final : public ProgressSink {
 public:
  explicit CallbackProgress(std::function<void(double, const std::string&)> fn) : fn_(std::move(fn)) {}
  void Report(double fraction, const std::string& stage) override {
    std::lock_guard<std::mutex> lock(mutex_);
    fn_(fraction, stage);
  }

 private:
  std::mutex mutex_;
  std::function<void(double, const std::string&)> fn_;
};

// Maps [0, 1] of a sub-job onto [begin, end] of the parent's progress.
class SubProgress final : public ProgressSink {
 public:
  SubProgress(ProgressSink& parent, double begin, double end) : parent_(parent), begin_(begin), end_(end) {}
  void Report(double fraction, const std::string& stage) override {
    parent_.Report(begin_ + (end_ - begin_) * fraction, stage);
  }

 private:
  ProgressSink& parent_;
  double begin_;
  double end_;
};

// Set from any thread (the GUI's Cancel button); polled by the job once per iteration.
class CancelToken {
 public:
  void Cancel() { cancelled_.store(true, std::memory_order_relaxed); }
  bool IsCancelled() const { return cancelled_.load(std::memory_order_relaxed); }

 private:
  std::atomic<bool> cancelled_{false};
};

}  // namespace scanreg
