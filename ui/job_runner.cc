#include "ui/job_runner.h"

#include <QMetaObject>
#include <QPointer>
#include <chrono>

namespace scanreg::ui {
namespace {

// Forwards core progress to the GUI thread, at most every 50 ms.
class QueuedProgress final : public ProgressSink {
 public:
  explicit QueuedProgress(JobRunner* runner) : runner_(runner) {}
  void Report(double fraction, const std::string& stage) override {
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    if (stage == last_stage_ && now - last_ < std::chrono::milliseconds(50) && fraction < 1.0) return;
    last_ = now;
    last_stage_ = stage;
    const QString text = QString::fromStdString(stage);
    QPointer<JobRunner> runner = runner_;
    QMetaObject::invokeMethod(
        runner_, [runner, fraction, text] { if (runner) emit runner->Progress(fraction, text); }, Qt::QueuedConnection);
  }

 private:
  JobRunner* runner_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point last_{};
  std::string last_stage_;
};

}  // namespace

JobRunner::JobRunner(QObject* parent) : QObject(parent) {}

JobRunner::~JobRunner() {
  if (cancel_) cancel_->Cancel();
  Join();
}

void JobRunner::Join() {
  if (thread_.joinable()) thread_.join();
}

bool JobRunner::StartErased(const QString& title, ErasedJob job, std::function<void(std::any&)> done) {
  if (busy_) return false;
  Join();  // a finished worker may not have been joined yet
  busy_ = true;
  cancel_ = std::make_shared<CancelToken>();
  emit Started(title);
  auto cancel = cancel_;
  thread_ = std::thread([this, title, job = std::move(job), done = std::move(done), cancel] {
    QueuedProgress progress(this);
    Expected<std::any> result = job(progress, *cancel);
    QMetaObject::invokeMethod(
        this,
        [this, title, done, result = std::move(result)]() mutable {
          busy_ = false;  // the callback may start the next job
          if (result.ok()) {
            done(result.value());
            emit Succeeded(title);
          } else {
            emit Failed(title, QString::fromStdString(result.error().message),
                        result.error().code == ErrorCode::kCancelled);
          }
        },
        Qt::QueuedConnection);
  });
  return true;
}

void JobRunner::Cancel() {
  if (cancel_) cancel_->Cancel();
}

}  // namespace scanreg::ui
