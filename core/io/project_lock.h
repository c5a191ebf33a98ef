// Runs that cannot trample each other (issue 16, item 4): one writer per project. A command that
// will save a project holds a lock file beside it, ".<name>.lock", with its process id and what it
// does; a second writer refuses at once with that information instead of silently overwriting the
// first one's result minutes later. A lock left by a process that no longer runs (kill -9) is
// taken over.
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
  ~ProjectLock();  // removes the lock file

  const std::filesystem::path& path() const { return path_; }

 private:
  explicit ProjectLock(std::filesystem::path path) : path_(std::move(path)) {}
  std::filesystem::path path_;
};

// The lock file of a project: ".<name>.lock" in its folder.
std::filesystem::path ProjectLockPath(const std::filesystem::path& project);

}  // namespace scanreg::io
