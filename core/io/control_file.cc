#include "core/io/control_file.h"

#include <cmath>
#include <set>

#include "core/common/atomic_file.h"
#include "core/io/text_parse.h"

namespace scanreg::io {
namespace {

constexpr std::uintmax_t kMaxBytes = 64u << 20;

bool IsSeparator(char c) { return c == ',' || c == ';' || c == '\t' || c == ' '; }

// Splits a line into fields: separators are , ; tab or space (runs of spaces/tabs count once);
// a field may be quoted with "" (a doubled quote inside stands for one). False when a quote is not
// closed.
bool SplitFields(std::string_view line, std::vector<std::string>* fields) {
  fields->clear();
  std::size_t i = 0;
  auto skip_blanks = [&] {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
  };
  skip_blanks();
  while (i < line.size()) {
    std::string field;
    if (line[i] == '"') {
      ++i;
      for (;; ++i) {
        if (i >= line.size()) return false;
        if (line[i] != '"') {
          field += line[i];
        } else if (i + 1 < line.size() && line[i + 1] == '"') {
          field += '"';
          ++i;
        } else {
          ++i;
          break;
        }
      }
    } else {
      while (i < line.size() && !IsSeparator(line[i])) field += line[i++];
    }
    fields->push_back(std::move(field));
    skip_blanks();
    if (i < line.size() && (line[i] == ',' || line[i] == ';')) {
      ++i;
      skip_blanks();
      if (i >= line.size()) fields->emplace_back();  // a trailing separator: an empty last field
    }
  }
  return true;
}

// Exactly one finite number.
bool ParseDouble(const std::string& text, double* v) {
  double two[2];
  const NumberParse parse = ParseNumbers(text, two, 2);
  if (parse.count != 1 || parse.status != ParseStatus::kOk) return false;
  *v = two[0];
  return true;
}

}  // namespace

Expected<std::vector<ControlPoint>> ReadControlFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec) && std::filesystem::file_size(path, ec) > kMaxBytes) {
    return MakeError(ErrorCode::kInvalidArgument,
                     path.string() + ": over 64 MB; a control file holds one line per control point");
  }
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  LineReader lines(*text);
  std::string_view line;
  std::vector<ControlPoint> points;
  std::set<std::string> names;
  std::vector<std::string> f;
  bool first = true;
  while (lines.Next(&line)) {
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (IsBlank(line)) continue;
    std::string_view trimmed = line;
    while (!trimmed.empty() && (trimmed[0] == ' ' || trimmed[0] == '\t')) trimmed.remove_prefix(1);
    if (trimmed[0] == '#') continue;
    const std::string at = AtLine(path, lines.line_number());
    if (!SplitFields(line, &f)) return MakeError(ErrorCode::kParseError, at + "a quote is not closed");
    double dummy = 0;
    if (first && f.size() >= 2 && !ParseDouble(f[1], &dummy)) {  // a header line
      first = false;
      continue;
    }
    first = false;
    if (f.size() < 4 || f.size() > 5) {
      return MakeError(ErrorCode::kParseError, at + "expected name, E, N, H and an optional sigma in metres (" +
                                                   std::to_string(f.size()) + " fields found)");
    }
    ControlPoint p;
    p.name = f[0];
    if (p.name.empty()) return MakeError(ErrorCode::kParseError, at + "the point name is empty");
    for (int k = 0; k < 3; ++k) {
      if (!ParseDouble(f[1 + k], &p.position[k])) {
        return MakeError(ErrorCode::kParseError, at + "the " + std::string(k == 0 ? "E" : k == 1 ? "N" : "H") +
                                                     " coordinate " + QuoteToken(f[1 + k]) + " is not a finite number");
      }
    }
    if (f.size() == 5 && !f[4].empty()) {
      double s = 0;
      if (!ParseDouble(f[4], &s) || !(s > 0 && s <= 10)) {
        return MakeError(ErrorCode::kParseError,
                         at + "sigma " + QuoteToken(f[4]) + " must be a number of metres in (0, 10] (e.g. 0.002)");
      }
      p.sigma_m = s;
    }
    if (!names.insert(p.name).second) {
      return MakeError(ErrorCode::kParseError, at + "control point " + QuoteToken(p.name) + " is given twice");
    }
    points.push_back(std::move(p));
  }
  if (points.empty()) {
    return MakeError(ErrorCode::kParseError,
                     path.string() + ": no control point found; expected lines of name, E, N, H [, sigma_m]");
  }
  return points;
}

Status MarkCheckPoints(const std::vector<std::string>& names, std::vector<ControlPoint>* points) {
  for (const std::string& name : names) {
    bool found = false;
    for (ControlPoint& c : *points)
      if (c.name == name) c.check = found = true;
    if (!found) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "check point " + QuoteToken(name) + " is not a control point" +
                           (points->empty() ? " (there are no control points; give the control file)" : ""));
    }
  }
  return Status::Ok();
}

Status WriteControlFile(const std::filesystem::path& path, const std::vector<ControlPoint>& points) {
  std::string text = "name,E,N,H,sigma_m\n";
  char buf[32];
  for (const ControlPoint& p : points) {
    const bool quote = p.name.find_first_of(",; \t\"") != std::string::npos;
    std::string name = p.name;
    if (quote) {
      name = "\"";
      for (char c : p.name) name += c == '"' ? std::string("\"\"") : std::string(1, c);
      name += "\"";
    }
    text += name;
    for (int k = 0; k < 3; ++k) text += ',' + std::string(buf, AppendNumber(buf, p.position[k]));
    text += ',';
    if (p.sigma_m) text.append(buf, AppendNumber(buf, *p.sigma_m));
    text += '\n';
  }
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(text); !s) return s;
  return file.Commit();
}

}  // namespace scanreg::io
