#include "app/cli_args.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace scanreg::cli {
namespace {

Error BadOption(const std::string& command, const std::string& message) {
  return MakeError(ErrorCode::kInvalidArgument,
                   command + ": " + message + " (see 'scanreg-cli " + command + " --help')");
}

}  // namespace

Expected<Args> Args::Parse(const std::string& command, const std::vector<std::string>& argv,
                           const std::vector<OptionSpec>& specs) {
  Args args;
  args.command_ = command;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.rfind("--", 0) != 0 || a == "--") {
      args.positional_.push_back(a);
      continue;
    }
    std::string name = a.substr(2), value;
    const auto eq = name.find('=');
    const bool inline_value = eq != std::string::npos;
    if (inline_value) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& s : specs)
      if (s.name == name) spec = &s;
    if (!spec) return BadOption(command, "unknown option '--" + name + "'");
    if (spec->takes_value && !inline_value) {
      if (i + 1 >= argv.size()) return BadOption(command, "option '--" + name + "' needs a value");
      value = argv[++i];
    } else if (!spec->takes_value && inline_value) {
      return BadOption(command, "option '--" + name + "' takes no value");
    }
    if (!spec->repeatable && args.values_.count(name)) {
      return BadOption(command, "option '--" + name + "' given twice");
    }
    args.values_[name].push_back(value);
  }
  return args;
}

std::optional<std::string> Args::Get(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second.back();
}

std::vector<std::string> Args::GetAll(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? std::vector<std::string>{} : it->second;
}

Expected<int> Args::GetInt(const std::string& name, int fallback, int min, int max) const {
  const auto v = Get(name);
  if (!v) return fallback;
  int out = 0;
  const auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || ptr != v->data() + v->size() || out < min || out > max) {
    return BadOption(command_, "--" + name + " must be an integer from " + std::to_string(min) + " to " +
                                   std::to_string(max) + ", not '" + *v + "'");
  }
  return out;
}

Expected<double> Args::GetDouble(const std::string& name, double fallback, double min, double max) const {
  const auto v = Get(name);
  if (!v) return fallback;
  double out = 0;
  const auto [ptr, ec] = std::from_chars(v->data(), v->data() + v->size(), out);
  if (ec != std::errc() || ptr != v->data() + v->size() || !std::isfinite(out) || out < min || out > max) {
    char range[96];
    std::snprintf(range, sizeof range, "%g to %g", min, max);
    return BadOption(command_, "--" + name + " must be a number from " + range + ", not '" + *v + "'");
  }
  return out;
}

Expected<std::pair<int, int>> Args::GetSize(const std::string& name, std::pair<int, int> fallback) const {
  const auto v = Get(name);
  if (!v) return fallback;
  const auto x = v->find('x');
  int w = 0, h = 0;
  bool ok = x != std::string::npos;
  if (ok) {
    const auto r1 = std::from_chars(v->data(), v->data() + x, w);
    const auto r2 = std::from_chars(v->data() + x + 1, v->data() + v->size(), h);
    ok = r1.ec == std::errc() && r1.ptr == v->data() + x && r2.ec == std::errc() && r2.ptr == v->data() + v->size();
  }
  if (!ok || w < 8 || h < 8 || w > 100000 || h > 50000) {
    return BadOption(command_, "--" + name + " must be WIDTHxHEIGHT like 3000x750 (each at least 8), not '" + *v + "'");
  }
  return std::make_pair(w, h);
}

}  // namespace scanreg::cli
