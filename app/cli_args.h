// Command-line parsing for scanreg-cli: positional arguments and --options, each option declared
// by the subcommand so that an unknown or malformed option is a clear error.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::cli {

struct OptionSpec {
  std::string name;        // without the leading "--"
  bool takes_value = true;
  bool repeatable = false;
  std::string help;        // "VALUE  what it does"
};

class Args {
 public:
  // Parses argv (after the subcommand) against the declared options.
  static Expected<Args> Parse(const std::string& command, const std::vector<std::string>& argv,
                              const std::vector<OptionSpec>& specs);

  const std::vector<std::string>& positional() const { return positional_; }
  bool Has(const std::string& name) const { return values_.count(name) > 0; }
  std::optional<std::string> Get(const std::string& name) const;
  std::vector<std::string> GetAll(const std::string& name) const;

  // Typed getters: the default when absent, an error naming the option when malformed or out of range.
  Expected<int> GetInt(const std::string& name, int fallback, int min, int max) const;
  Expected<double> GetDouble(const std::string& name, double fallback, double min, double max) const;
  // "WxH" (e.g. 3000x750).
  Expected<std::pair<int, int>> GetSize(const std::string& name, std::pair<int, int> fallback) const;

 private:
  std::string command_;
  std::vector<std::string> positional_;
  std::map<std::string, std::vector<std::string>> values_;
};

}  // namespace scanreg::cli
