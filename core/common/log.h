// Process-wide log of core messages. The CLI prints them to stderr; the GUI shows them in its log
// dock by installing a handler.
#pragma once

#include <functional>
#include <string>

namespace scanreg {

enum class LogLevel { kDebug, kInfo, kWarning, kError };

using LogHandler = std::function<void(LogLevel, const std::string&)>;

// Replaces the handler (thread-safe). An empty handler restores the default (stderr, info and up).
void SetLogHandler(LogHandler handler);
void Log(LogLevel level, const std::string& message);

inline void LogInfo(const std::string& message) { Log(LogLevel::kInfo, message); }
inline void LogWarning(const std::string& message) { Log(LogLevel::kWarning, message); }
inline void LogError(const std::string& message) { Log(LogLevel::kError, message); }

}  // namespace scanreg
