#include "core/io/project_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/common/log.h"

namespace scanreg::io {
namespace {

// The pid and description in a lock file (what its holder wrote); pid 0 when unreadable.
std::pair<long, std::string> ReadLock(const std::filesystem::path& path) {
  std::ifstream in(path);
  long pid = 0;
  std::string what;
  if (in >> pid) std::getline(in >> std::ws, what);
  for (char& c : what)
    if (static_cast<unsigned char>(c) < 0x20) c = '?';
  return {pid, what.substr(0, 200)};
}

}  // namespace

std::filesystem::path ProjectLockPath(const std::filesystem::path& project) {
  return project.parent_path() / ("." + project.filename().string() + ".lock");
}

// The lock is an flock() on the lock file, held as long as the holder keeps it open: the kernel
// releases it when the holder exits, however it exits (kill -9 included), so a stale lock needs no
// guess about process ids, and two runs that find one cannot both take it over. The pid and the
// command written into the file are for the message only.
Expected<ProjectLock> ProjectLock::Acquire(const std::filesystem::path& project, const std::string& what) {
  const std::filesystem::path path = ProjectLockPath(std::filesystem::absolute(project));
  for (int attempt = 0; attempt < 5; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      return MakeError(ErrorCode::kIoError, "cannot create the lock file '" + path.string() + "' beside project '" +
                                                project.string() + "': " + std::strerror(errno) +
                                                " (is the folder writable?)");
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      if (errno != EWOULDBLOCK && errno != EINTR) {  // a file system without locks (some network mounts)
        const std::string why = std::strerror(errno);
        ::close(fd);
        LogWarning("cannot lock '" + path.string() + "' (" + why +
                   "); make sure no other run writes project '" + project.string() + "' meanwhile");
        return ProjectLock(std::filesystem::path(), -1);
      }
      ::close(fd);
      const auto [pid, holder] = ReadLock(path);
      return MakeError(ErrorCode::kConflict,
                       "project '" + project.string() + "' is being written by another run (process " +
                           (pid > 0 ? std::to_string(pid) : std::string("?")) + ": " + holder +
                           "); wait for it to finish, then run this again");
    }
    // A holder that was releasing removed the file between our open and flock: ours is an orphan
    // inode, and the next run would create another file. Only the file at the path counts.
    struct stat at_path {}, ours {};
    if (::stat(path.c_str(), &at_path) != 0 || ::fstat(fd, &ours) != 0 || at_path.st_ino != ours.st_ino ||
        at_path.st_dev != ours.st_dev) {
      ::close(fd);
      continue;
    }
    std::ostringstream text;
    text << ::getpid() << " " << what << "\n";
    const std::string s = text.str();
    if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, s.data(), s.size(), 0) != static_cast<ssize_t>(s.size())) {
      ::close(fd);
      return MakeError(ErrorCode::kIoError, "cannot write the lock file '" + path.string() + "' (disk full?)");
    }
    return ProjectLock(path, fd);
  }
  return MakeError(ErrorCode::kConflict, "project '" + project.string() + "': could not take its lock file '" +
                                             path.string() + "'; other runs keep taking and releasing it");
}

ProjectLock::ProjectLock(ProjectLock&& other) noexcept : path_(std::move(other.path_)), fd_(other.fd_) {
  other.path_.clear();
  other.fd_ = -1;
}

ProjectLock::~ProjectLock() {
  if (fd_ < 0) return;
  // Removed while still held, so that no one locks the file being removed; then released.
  std::error_code ec;
  std::filesystem::remove(path_, ec);
  ::close(fd_);
}

}  // namespace scanreg::io
