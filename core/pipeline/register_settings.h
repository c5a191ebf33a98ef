// The registration options a project records and re-uses. The CLI's flags, the project file's
// `settings` and the GUI's registration settings all go through this one table, so re-running a
// project uses the methods, noise and distances it was registered with. Each setting has a key
// (in the project file), a CLI flag and a GUI label; errors name the setting by its label and each
// front end words it its own way.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/io/project.h"
#include "core/pipeline/register_options.h"

namespace scanreg::pipeline {

struct RegisterSetting {
  const char* key;                   // project file: settings["register.<name>"]
  const char* flag;                  // scanreg-cli register --<flag>
  const char* label;                 // GUI and error messages
  std::vector<std::string> choices;  // allowed values; empty for numbers and booleans
  bool boolean = false;              // "true" / "false"
};

// Every setting, in the order the GUI lists them.
const std::vector<RegisterSetting>& RegisterSettings();

// The value of a setting in `options`, as stored in the project (numbers round-trip exactly).
std::string RegisterSettingValue(const RegisterOptions& options, const RegisterSetting& setting);
// Sets one setting; an error names the setting's label and the allowed values.
Status ApplyRegisterSetting(const RegisterSetting& setting, const std::string& value, RegisterOptions* options);

// `base` with every register.* setting of the project applied (unknown register.* keys are an
// error naming the key); other keys are ignored.
Expected<RegisterOptions> RegisterOptionsFromSettings(const std::map<std::string, std::string>& settings,
                                                      RegisterOptions base = {});
// The options to register `project` with: the defaults (refining from the current poses when every
// scan's pose was imported), then the project's saved settings.
Expected<RegisterOptions> ProjectRegisterOptions(const io::Project& project);

// Writes every setting of `options` into the project's settings.
void StoreRegisterSettings(const RegisterOptions& options, std::map<std::string, std::string>* settings);

}  // namespace scanreg::pipeline
