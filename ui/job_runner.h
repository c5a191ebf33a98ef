// Runs one long core job at a time off the GUI thread (STYLE.md convention 8). The job gets a
// ProgressSink and a CancelToken; progress comes back to the GUI thread through queued signals,
// and the job's typed result goes to the callback of whoever started it, on the GUI thread. No Qt
// or VTK object is touched from the worker.
#pragma once

#include <QObject>
#include <QString>
#include <any>
#include <atomic>
#include <functional>
#include <memory>
#include <thread>

#include "core/common/expected.h"
#include "core/common/progress.h"

namespace scanreg::ui {

class JobRunner : public QObject {
  Q_OBJECT

 public:
  template <typename T>
  using Job = std::function<Expected<T>(ProgressSink&, const CancelToken&)>;
  template <typename T>
  using Done = std::function<void(T&)>;

  explicit JobRunner(QObject* parent = nullptr);
  ~JobRunner() override;  // cancels and joins a running job

  bool busy() const { return busy_; }
  // Starts the job; returns false (and does nothing) while another job runs. On success `done`
  // gets the result (on the GUI thread), then Succeeded is emitted; on failure, Failed.
  template <typename T>
  bool Start(const QString& title, Job<T> job, Done<T> done) {
    return StartErased(
        title,
        [job = std::move(job)](ProgressSink& progress, const CancelToken& cancel) -> Expected<std::any> {
          Expected<T> r = job(progress, cancel);
          if (!r) return r.error();
          return std::any(std::make_shared<T>(std::move(*r)));
        },
        [done = std::move(done)](std::any& result) {
          if (done) done(**std::any_cast<std::shared_ptr<T>>(&result));
        });
  }
  void Cancel();

 signals:
  void Started(const QString& title);
  void Progress(double fraction, const QString& stage);
  // Exactly one of the two per job (Succeeded after the starter's callback).
  void Succeeded(const QString& title);
  void Failed(const QString& title, const QString& message, bool cancelled);

 private:
  using ErasedJob = std::function<Expected<std::any>(ProgressSink&, const CancelToken&)>;
  bool StartErased(const QString& title, ErasedJob job, std::function<void(std::any&)> done);
  void Join();

  bool busy_ = false;
  std::shared_ptr<CancelToken> cancel_;
  std::thread thread_;
};

}  // namespace scanreg::ui
