// Registration → Settings…: the project's registration settings (pipeline::RegisterSettings(): the
// same table as the CLI's flags and the project file), shown with their current values and
// edited; OK stores them in the project as an undoable edit (MainWindow::SetRegisterOptions).
#pragma once

#include <QDialog>
#include <vector>

#include "core/common/expected.h"
#include "core/pipeline/register_options.h"

class QLabel;

namespace scanreg::ui {

class RegisterSettingsDialog : public QDialog {
  Q_OBJECT
 public:
  RegisterSettingsDialog(const pipeline::RegisterOptions& options, QWidget* parent = nullptr);

  // The options with the fields' values; an error names the setting's label.
  Expected<pipeline::RegisterOptions> Options() const;
  // One editor per setting, in pipeline::RegisterSettings() order (QComboBox, QCheckBox or QLineEdit).
  QWidget* field(int i) const { return fields_[i]; }
  // Closes with QDialog::accepted only when every field is valid; otherwise names the bad one.
  void accept() override;

 private:
  pipeline::RegisterOptions base_;
  std::vector<QWidget*> fields_;
  QLabel* error_ = nullptr;
};

}  // namespace scanreg::ui
