#include "ui/register_settings_dialog.h"

#include <QCheckBox>
#include <QComboBox>
#include <QDialogButtonBox>
#include <QFormLayout>
#include <QLabel>
#include <QLineEdit>
#include <QVBoxLayout>

#include "core/pipeline/register_settings.h"

namespace scanreg::ui {

RegisterSettingsDialog::RegisterSettingsDialog(const pipeline::RegisterOptions& options, QWidget* parent)
    : QDialog(parent), base_(options) {
  setWindowTitle(tr("Registration settings"));
  auto* form = new QFormLayout;
  for (const pipeline::RegisterSetting& s : pipeline::RegisterSettings()) {
    const QString value = QString::fromStdString(pipeline::RegisterSettingValue(options, s));
    QWidget* field = nullptr;
    if (s.boolean) {
      auto* box = new QCheckBox;
      box->setChecked(value == "true");
      field = box;
    } else if (!s.choices.empty()) {
      auto* combo = new QComboBox;
      for (const std::string& c : s.choices) combo->addItem(QString::fromStdString(c));
      combo->setCurrentText(value);
      field = combo;
    } else {
      field = new QLineEdit(value);
    }
    field->setToolTip(tr("Project setting %1 (scanreg-cli register --%2)").arg(s.key, s.flag));
    form->addRow(QString(s.label).replace(0, 1, QString(s.label).at(0).toUpper()) + ":", field);
    fields_.push_back(field);
  }
  error_ = new QLabel;
  error_->setStyleSheet("color: #b03020");
  error_->setWordWrap(true);
  error_->hide();
  auto* buttons = new QDialogButtonBox(QDialogButtonBox::Ok | QDialogButtonBox::Cancel);
  connect(buttons, &QDialogButtonBox::accepted, this, &RegisterSettingsDialog::accept);
  connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
  auto* layout = new QVBoxLayout(this);
  layout->addWidget(
      new QLabel(tr("Saved in the project and used by every registration of it (here and in "
                    "scanreg-cli).")));
  layout->addLayout(form);
  layout->addWidget(error_);
  layout->addWidget(buttons);
}

Expected<pipeline::RegisterOptions> RegisterSettingsDialog::Options() const {
  pipeline::RegisterOptions options = base_;
  const auto& settings = pipeline::RegisterSettings();
  for (std::size_t i = 0; i < settings.size(); ++i) {
    QString value;
    if (auto* box = qobject_cast<QCheckBox*>(fields_[i])) value = box->isChecked() ? "true" : "false";
    if (auto* combo = qobject_cast<QComboBox*>(fields_[i])) value = combo->currentText();
    if (auto* line = qobject_cast<QLineEdit*>(fields_[i])) value = line->text().trimmed();
    if (Status s = pipeline::ApplyRegisterSetting(settings[i], value.toStdString(), &options); !s) return s.error();
  }
  return options;
}

void RegisterSettingsDialog::accept() {
  const Expected<pipeline::RegisterOptions> options = Options();
  if (!options) {
    QString message = QString::fromStdString(options.error().message);
    message[0] = message[0].toUpper();
    error_->setText(message);
    error_->show();
    return;
  }
  QDialog::accept();
}

}  // namespace scanreg::ui
