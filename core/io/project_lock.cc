#include "core/io/project_lock.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace scanreg::io {
namespace {

// The pid and description in an existing lock file; pid 0 when unreadable.
std::pair<long, std::string> ReadLock(const std::filesystem::path& path) {
  std::ifstream in(path);
  long pid = 0;
  std::string what;
  if (in >> pid) std::getline(in >> std::ws, what);
  for (char& c : what)
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  return {pid, what.substr(0, 200)};
}

bool Running(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH); }

}  // namespace

std::filesystem::path ProjectLockPath(const std::filesystem::path& project) {
  return project.parent_path() / ("." + project.filename().string() + ".lock");
}

Expected<ProjectLock> ProjectLock::Acquire(const std::filesystem::path& project, const std::string& what) {
  const std::filesystem::path path = ProjectLockPath(std::filesystem::absolute(project));
  for (int attempt = 0; attempt < 3; ++attempt) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      std::ostringstream text;
      text << ::getpid() << " " << what << "\n";
      const std::string s = text.str();
      const bool ok = ::write(fd, s.data(), s.size()) == static_cast<ssize_t>(s.size());
      ::close(fd);
      if (!ok) {
        std::filesystem::remove(path);
        return MakeError(ErrorCode::kIoError, "cannot write the lock file '" + path.string() + "' (disk full?)");
      }
      return ProjectLock(path);
    }
    if (errno != EEXIST) {
      return MakeError(ErrorCode::kIoError, "cannot create the lock file '" + path.string() + "' beside project '" +
                                                project.string() + "': " + std::strerror(errno) +
                                                " (is the folder writable?)");
    }
    const auto [pid, holder] = ReadLock(path);
    if (Running(pid)) {
      return MakeError(ErrorCode::kFailed, "project '" + project.string() + "' is being written by another run (process " +
                                               std::to_string(pid) + ": " + holder +
                                               "); wait for it to finish, then run this again");
    }
    // Left by a process that no longer runs (or unreadable): take it over.
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
  return MakeError(ErrorCode::kFailed, "project '" + project.string() + "': could not take its lock file '" +
                                           path.string() + "'; another run keeps creating it");
}

ProjectLock::ProjectLock(ProjectLock&& other) noexcept : path_(std::move(other.path_)) { other.path_.clear(); }

ProjectLock::~ProjectLock() {
  if (path_.empty()) return;
  std::error_code ec;
  std::filesystem::remove(path_, ec);
}

}  // namespace scanreg::io
