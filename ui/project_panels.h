// Dock panels over the project: the scan list, the confusion matrix heat map and the log.
#pragma once

#include <Eigen/Core>
#include <QPlainTextEdit>
#include <QSet>
#include <QTableWidget>
#include <vector>

#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/pipeline/scan_previews.h"

namespace scanreg::ui {

// One row per scan: name (with a check box: shown in the 3D view), grid size, valid points,
// status, position, error against the reference.
class ScanListPanel : public QTableWidget {
  Q_OBJECT

 public:
  explicit ScanListPanel(QWidget* parent = nullptr);
  void Show(const io::Project& project, const std::vector<pipeline::ScanPreview>& scans);

 signals:
  void ScanVisibilityChanged(const QString& name, bool visible);

 private:
  QSet<QString> hidden_;  // scans the user unchecked; kept across Show()
};

// C(i, j) as a heat map with the counts; the diagonal (feature counts) in grey.
class ConfusionPanel : public QTableWidget {
  Q_OBJECT

 public:
  explicit ConfusionPanel(QWidget* parent = nullptr);
  void Show(const Eigen::MatrixXi& confusion, const std::vector<std::string>& names);
};

// Core log messages (they arrive on any thread; Append must be called on the GUI thread).
class LogPanel : public QPlainTextEdit {
  Q_OBJECT

 public:
  explicit LogPanel(QWidget* parent = nullptr);
  void Append(const QString& level, const QString& message);  // with the time of day
  void Header(const QString& title);  // a line that starts a run: "── Registering — 2026-12-02 04:55:12 ──"
};

}  // namespace scanreg::ui
