// Fast text parsing shared by the ASCII readers (PTX, PLY, pose files): a line splitter that
// counts lines for error messages and number parsing with std::from_chars (no iostream).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/common/expected.h"

namespace scanreg::io {

// The whole file in memory (binary, no newline translation).
Expected<std::string> ReadWholeFile(const std::filesystem::path& path);

// Splits text into lines ('\n' or "\r\n" endings) and numbers them from 1.
class LineReader {
 public:
  explicit LineReader(std::string_view text, std::size_t offset = 0, long first_line = 1)
      : text_(text), pos_(offset), next_line_(first_line) {}

  // The next line without its ending; false at the end of the text.
  bool Next(std::string_view* line);
  // Skips lines holding only white space; false when the text ends first.
  bool SkipBlankLines();
  // 1-based number of the line last returned by Next() (0 before the first call).
  long line_number() const { return next_line_ - 1; }
  std::size_t offset() const { return pos_; }
  bool AtEnd() const { return pos_ >= text_.size(); }
  // Number of lines from the current position to the end of the text.
  std::size_t CountRemainingLines() const;

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  long next_line_ = 1;
};

enum class ParseStatus { kOk, kBadToken, kNonFinite };

struct NumberParse {
  int count = 0;  // numbers parsed before the end of the line or a failure
  ParseStatus status = ParseStatus::kOk;
  std::string_view token;  // the offending token when status != kOk
};

// Parses up to max_count white-space separated numbers (float or double) from line; tokens after
// max_count are not looked at. NaN and infinities are reported as kNonFinite.
NumberParse ParseNumbers(std::string_view line, float* out, int max_count);
NumberParse ParseNumbers(std::string_view line, double* out, int max_count);

// Splits off the first white-space separated token of *line (empty when none).
std::string_view NextToken(std::string_view* line);

bool IsBlank(std::string_view line);

// A token quoted for an error message (control bytes escaped), shortened when long.
std::string QuoteToken(std::string_view token);

// "<path>, line <n>: " prefix for error messages.
std::string AtLine(const std::filesystem::path& path, long line);

// Shortest text that reads back to exactly the same value; returns the end of the text.
// The buffer needs 32 characters.
char* AppendNumber(char* out, float value);
char* AppendNumber(char* out, double value);

// Lower-case extension including the dot (".ptx"), for dispatch.
std::string LowerExtension(const std::filesystem::path& path);

}  // namespace scanreg::io
