#include "core/common/log.h"

#include "core/common/expected.h"

#include <cstdio>
#include <mutex>

namespace scanreg {
namespace {

std::mutex& LogMutex() {
  static std::mutex mutex;
  return mutex;
}

LogHandler& Handler() {
  static LogHandler handler;
  return handler;
}

const char* LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarning: return "warning";
    case LogLevel::kError: return "error";
  }
  return "";
}

}  // namespace

void SetLogHandler(LogHandler handler) {
  std::lock_guard<std::mutex> lock(LogMutex());
  Handler() = std::move(handler);
}

void Log(LogLevel level, const std::string& message) {
  const std::string line = EscapeControlBytes(message);  // one printable line, whatever it quotes
  std::lock_guard<std::mutex> lock(LogMutex());
  if (Handler()) {
    Handler()(level, line);
  } else if (level >= LogLevel::kInfo) {
    std::fprintf(stderr, "[%s] %s\n", LevelName(level), line.c_str());
  }
}

}  // namespace scanreg
