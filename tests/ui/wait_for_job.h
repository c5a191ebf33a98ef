// Waiting for the main window's worker in Qt Test programs (the event loop keeps running).
#pragma once

#include <QElapsedTimer>
#include <QSignalSpy>
#include <QtTest/QtTest>

#include "ui/job_runner.h"
#include "ui/main_window.h"

namespace scanreg::test {

// Waits for the running job; returns true when it succeeded. *cancelled: whether a failure was a cancel.
inline bool WaitForJob(ui::MainWindow& window, int timeout_ms, bool* cancelled = nullptr) {
  QSignalSpy ok(window.jobs(), &ui::JobRunner::Succeeded);
  QSignalSpy failed(window.jobs(), &ui::JobRunner::Failed);
  QElapsedTimer timer;
  timer.start();
  while (ok.isEmpty() && failed.isEmpty() && timer.elapsed() < timeout_ms) QTest::qWait(50);
  if (!failed.isEmpty() && cancelled) *cancelled = failed.first().at(2).toBool();
  return !ok.isEmpty();
}

}  // namespace scanreg::test
