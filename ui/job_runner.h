// Runs one long core job at a time off the GUI thread (STYLE.md convention 8). The job gets a
// ProgressSink and a CancelToken; progress and the result come back to the GUI thread by value
// through queued signals. No Qt or VTK object is touched from the worker.
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
  // The job returns its result type-erased in a std::any, or an error.
  using Job = std::function<Expected<std::any>(ProgressSink&, const CancelToken&)>;

  explicit JobRunner(QObject* parent = nullptr);
  ~JobRunner() override;  // cancels and joins a running job

  bool busy() const { return busy_; }
  // Starts the job; returns false (and does nothing) while another job runs.
  bool Start(const QString& title, Job job);
  void Cancel();

 signals:
  void Started(const QString& title);
  void Progress(double fraction, const QString& stage);
  // Exactly one of the two per job.
  void Succeeded(const QString& title, std::any result);
  void Failed(const QString& title, const QString& message, bool cancelled);

 private:
  void Join();

  bool busy_ = false;
  std::shared_ptr<CancelToken> cancel_;
  std::thread thread_;
};

}  // namespace scanreg::ui

Q_DECLARE_METATYPE(std::any)
