// Runs that cannot trample each other (issue 16, item 4): one writer per project. A command that
// will save a project holds a lock on a file beside it, ".<name>.lock" (flock; the file says which
// process and what it does); a second writer refuses at once with that information instead of
// silently overwriting the first one's result minutes later. The kernel drops the lock of a
// process that no longer runs (kill -9), so the next run takes it. On a file system without locks
// (some network mounts) Acquire warns and returns a lock that holds nothing.
#pragma once

#include <filesystem>
#include <string>

#include "core/common/expected.h"

namespace scanreg::io {

class ProjectLock {
 public:
  // what: the command, e.g. "scanreg-cli register"; shown to a second writer.
  static Expected<ProjectLock> Acquire(const std::filesystem::path& project, const std::string& what);
  ProjectLock(ProjectLock&& other) noexcept;
  ProjectLock& operator=(ProjectLock&&) = delete;
  ProjectLock(const ProjectLock&) = delete;
  ~ProjectLock();  // removes the lock file and releases the lock

  const std::filesystem::path& path() const { return path_; }

 private:
  ProjectLock(std::filesystem::path path, int fd) : path_(std::move(path)), fd_(fd) {}
  std::filesystem::path path_;
  int fd_ = -1;  // open, with the flock held
};

// The lock file of a project: ".<name>.lock" in its folder.
std::filesystem::path ProjectLockPath(const std::filesystem::path& project);

}  // namespace scanreg::io
