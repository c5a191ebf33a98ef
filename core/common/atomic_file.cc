#include "core/common/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace scanreg {

namespace {
constexpr std::size_t kBufferBytes = 4 << 20;
std::atomic<unsigned> g_counter{0};

// ".<name>.tmp-": the prefix of the temporary files of `target` (hidden, so that a listing or a
// glob of the folder does not pick them up).
std::string TempPrefix(const std::filesystem::path& target) { return "." + target.filename().string() + ".tmp-"; }

// The pid in ".<name>.tmp-<pid>-<n>" (all of <pid> and <n> digits), or 0 when `file` is not one of our
// temporaries.
long TemporaryOwner(const std::string& file) {
  if (file.size() < 2 || file[0] != '.') return 0;
  const std::size_t at = file.rfind(".tmp-");
  if (at == std::string::npos || at == 0) return 0;
  const char* p = file.c_str() + at + 5;
  char* end = nullptr;
  const long pid = std::strtol(p, &end, 10);
  if (pid <= 0 || end == p || *end != '-') return 0;
  const char* n = end + 1;
  if (*n == '\0') return 0;
  for (; *n != '\0'; ++n)
    if (*n < '0' || *n > '9') return 0;
  return pid;
}

// Removes the temporaries that processes killed mid-write left in the target's folder (of any
// file there, so that a killed export of one scan does not stay behind until that scan is
// exported again). A temporary whose process still runs is never touched.
void RemoveStaleTemporaries(const std::filesystem::path& target) {
  std::error_code ec;
  const std::filesystem::path dir = target.has_parent_path() ? target.parent_path() : ".";
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const long pid = TemporaryOwner(e.path().filename().string());
    if (pid == 0) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours to judge)
    std::error_code rm;
    if (e.is_regular_file(rm)) std::filesystem::remove(e.path(), rm);
  }
}

}  // namespace

AtomicFile::AtomicFile(std::filesystem::path target) : target_(std::move(target)) {
  temp_ = target_.parent_path() /
          (TempPrefix(target_) + std::to_string(::getpid()) + "-" + std::to_string(g_counter.fetch_add(1)));
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

Status AtomicFile::Fail(const std::string& what) {
  const std::string reason = std::strerror(errno);
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  return MakeError(ErrorCode::kIoError, target_.string() + ": cannot " + what + " (" + reason +
                                            "); check that the folder exists, is writable and has free space");
}

Status AtomicFile::Open() {
  RemoveStaleTemporaries(target_);
  fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) return Fail("create a temporary file beside it");
  buffer_.reserve(kBufferBytes);
  return Status::Ok();
}

Status AtomicFile::Flush() {
  const char* p = buffer_.data();
  std::size_t left = buffer_.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      return Fail("write");
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  buffer_.clear();
  return Status::Ok();
}

Status AtomicFile::Write(std::string_view bytes) {
  if (fd_ < 0) return MakeError(ErrorCode::kIoError, target_.string() + ": write to a file that is not open");
  buffer_.append(bytes);
  if (buffer_.size() >= kBufferBytes) return Flush();
  return Status::Ok();
}

Status AtomicFile::CloseForExternalWriter() {
  if (fd_ >= 0) {
    if (Status s = Flush(); !s) return s;
    ::close(fd_);
    fd_ = -1;
  }
  return Status::Ok();
}

Status AtomicFile::Commit() {
  if (fd_ < 0) {
    fd_ = ::open(temp_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) return Fail("reopen the temporary file");
  } else if (Status s = Flush(); !s) {
    return s;
  }
  if (::fsync(fd_) != 0) return Fail("flush to disk");
  if (::close(fd_) != 0) {
    fd_ = -1;
    return Fail("close");
  }
  fd_ = -1;
  if (::rename(temp_.c_str(), target_.c_str()) != 0) return Fail("rename the temporary file over it");
  committed_ = true;
  std::filesystem::path dir = target_.parent_path();
  if (dir.empty()) dir = ".";
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return Status::Ok();
}

}  // namespace scanreg
