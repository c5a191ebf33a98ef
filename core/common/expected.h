// Error values and Expected<T>: how core functions report failure (STYLE.md, convention 3).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace scanreg {

enum class ErrorCode {
  kInvalidArgument,  // a nonsense option or parameter
  kIoError,          // a file could not be opened, read or written
  kParseError,       // a file's content is malformed
  kNotFound,         // a named file, scan or item does not exist
  kUnsupported,      // valid input we do not handle (yet)
  kCancelled,        // the user cancelled the job
  kFailed,           // an algorithm ran but its evidence is too weak
  kConflict,         // another run holds the file, or it changed on disk since it was read
};

const char* ErrorCodeName(ErrorCode code);

// Bytes below 0x20 and 0x7f as \xNN, so that a message quoting a file never drives the terminal
// and stays one line.
std::string EscapeControlBytes(std::string_view text);

struct Error {
  ErrorCode code = ErrorCode::kFailed;
  std::string message;  // names the file/line/scan and the next step

  std::string ToString() const { return std::string(ErrorCodeName(code)) + ": " + message; }
};

// Every error is one printable line, whatever file content it quotes.
inline Error MakeError(ErrorCode code, const std::string& message) { return Error{code, EscapeControlBytes(message)}; }

// A value or an error. Minimal C++17 stand-in for std::expected.
template <typename T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : data_(std::move(value)) {}        // NOLINT(google-explicit-constructor)
  Expected(Error error) : data_(std::move(error)) {}     // NOLINT(google-explicit-constructor)

  bool ok() const { return data_.index() == 0; }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<0>(data_); }
  const T& value() const& { return std::get<0>(data_); }
  // By value: `for (x : F().value())` must not iterate a temporary that is already gone.
  T value() && { return std::get<0>(std::move(data_)); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }

  const Error& error() const { return std::get<1>(data_); }

 private:
  std::variant<T, Error> data_;
};

// Success or an error, for functions with no value to return.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(Error error) : error_(std::move(error)), ok_(false) {}  // NOLINT(google-explicit-constructor)
  static Status Ok() { return Status(); }

  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const Error& error() const { return error_; }

 private:
  Error error_;
  bool ok_ = true;
};

}  // namespace scanreg
