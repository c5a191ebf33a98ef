#include "core/io/text_parse.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

namespace scanreg::io {

Expected<std::string> ReadWholeFile(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return MakeError(ErrorCode::kNotFound, path.string() + ": no such file; check the path");
  }
  if (std::filesystem::is_directory(path, ec)) {
    return MakeError(ErrorCode::kIoError, path.string() + " is a directory, not a file");
  }
  if (!std::filesystem::is_regular_file(path, ec)) {  // a FIFO would block, a device never end
    return MakeError(ErrorCode::kIoError, path.string() + " is not a regular file (a pipe or a device?)");
  }
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) {
    return MakeError(ErrorCode::kIoError,
                     path.string() + ": cannot open for reading (" + std::strerror(errno) + "); check permissions");
  }
  std::string text;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) text.resize(size);
  std::size_t got = text.empty() ? 0 : std::fread(text.data(), 1, text.size(), file.get());
  if (got != text.size() || std::ferror(file.get())) {
    return MakeError(ErrorCode::kIoError, path.string() + ": read error after " + std::to_string(got) + " bytes");
  }
  // The file may have grown since file_size (or size was unknown): read the rest.
  char chunk[65536];
  while (std::size_t n = std::fread(chunk, 1, sizeof(chunk), file.get())) text.append(chunk, n);
  return text;
}

bool LineReader::Next(std::string_view* line) {
  if (pos_ >= text_.size()) return false;
  const char* begin = text_.data() + pos_;
  const std::size_t left = text_.size() - pos_;
  const void* nl = std::memchr(begin, '\n', left);
  std::size_t len = nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - begin) : left;
  pos_ += nl ? len + 1 : len;
  if (len > 0 && begin[len - 1] == '\r') --len;
  *line = std::string_view(begin, len);
  ++next_line_;
  return true;
}

bool LineReader::SkipBlankLines() {
  while (pos_ < text_.size()) {
    const std::size_t save_pos = pos_;
    const long save_line = next_line_;
    std::string_view line;
    Next(&line);
    if (!IsBlank(line)) {
      pos_ = save_pos;
      next_line_ = save_line;
      return true;
    }
  }
  return false;
}

std::size_t LineReader::CountRemainingLines() const {
  if (pos_ >= text_.size()) return 0;
  const std::size_t n = static_cast<std::size_t>(std::count(text_.begin() + pos_, text_.end(), '\n'));
  return text_.back() == '\n' ? n : n + 1;
}

namespace {

inline bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

template <typename T>
NumberParse ParseNumbersImpl(std::string_view line, T* out, int max_count) {
  NumberParse result;
  const char* p = line.data();
  const char* end = p + line.size();
  while (result.count < max_count) {
    while (p < end && IsSpace(*p)) ++p;
    if (p == end) break;
    const char* start = p;
    if (*p == '+') ++p;  // from_chars rejects a leading '+'
    T value{};
    auto [ptr, ec] = std::from_chars(p, end, value);
    if (ec == std::errc::result_out_of_range) {
      // Denormal or huge: huge is non-finite in practice, tiny is zero.
      const char* tok_end = start;
      while (tok_end < end && !IsSpace(*tok_end)) ++tok_end;
      result.token = std::string_view(start, static_cast<std::size_t>(tok_end - start));
      const double d = std::strtod(std::string(result.token).c_str(), nullptr);
      if (std::isfinite(d) && std::fabs(d) < 1.0) {
        value = T(0);
        ptr = tok_end;
        ec = std::errc();
      } else {
        result.status = ParseStatus::kNonFinite;
        return result;
      }
    }
    if (ec != std::errc() || (ptr < end && !IsSpace(*ptr))) {
      const char* tok_end = start;
      while (tok_end < end && !IsSpace(*tok_end)) ++tok_end;
      result.token = std::string_view(start, static_cast<std::size_t>(tok_end - start));
      result.status = ParseStatus::kBadToken;
      return result;
    }
    if (!std::isfinite(value)) {
      result.token = std::string_view(start, static_cast<std::size_t>(ptr - start));
      result.status = ParseStatus::kNonFinite;
      return result;
    }
    out[result.count++] = value;
    p = ptr;
  }
  return result;
}

}  // namespace

NumberParse ParseNumbers(std::string_view line, float* out, int max_count) {
  return ParseNumbersImpl(line, out, max_count);
}
NumberParse ParseNumbers(std::string_view line, double* out, int max_count) {
  return ParseNumbersImpl(line, out, max_count);
}

std::string_view NextToken(std::string_view* line) {
  std::size_t i = 0;
  while (i < line->size() && IsSpace((*line)[i])) ++i;
  std::size_t j = i;
  while (j < line->size() && !IsSpace((*line)[j])) ++j;
  const std::string_view token = line->substr(i, j - i);
  line->remove_prefix(j);
  return token;
}

bool IsBlank(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return IsSpace(c); });
}

std::string QuoteToken(std::string_view token) {
  std::string s = EscapeControlBytes(token.substr(0, 40));
  if (token.size() > 40) s += "...";
  return "'" + s + "'";
}

std::string AtLine(const std::filesystem::path& path, long line) {
  return path.string() + ", line " + std::to_string(line) + ": ";
}

char* AppendNumber(char* out, float value) { return std::to_chars(out, out + 32, value).ptr; }
char* AppendNumber(char* out, double value) { return std::to_chars(out, out + 32, value).ptr; }

std::string LowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

}  // namespace scanreg::io
