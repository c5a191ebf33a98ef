#include "core/common/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <random>
#include <string>

namespace scanreg {

Status WriteFileAtomically(const std::filesystem::path& path, const std::function<Status(std::FILE*)>& write) {
  namespace fs = std::filesystem;
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    return MakeError(ErrorCode::kIoError, "cannot write '" + path.string() + "': folder '" + dir.string() +
                                              "' does not exist; create it or choose another location");
  }
  std::random_device rd;
  const fs::path tmp = dir / ("." + path.filename().string() + ".tmp" + std::to_string(rd()));
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (!file) {
    return MakeError(ErrorCode::kIoError, "cannot write '" + path.string() + "': " + std::strerror(errno) +
                                              "; check the folder's permissions and free space");
  }
  Status status = write(file);
  if (status.ok() && (std::fflush(file) != 0 || ::fsync(::fileno(file)) != 0 || std::ferror(file))) {
    status = MakeError(ErrorCode::kIoError, "writing '" + path.string() + "' failed: " + std::strerror(errno) +
                                                "; check free disk space");
  }
  if (std::fclose(file) != 0 && status.ok()) {
    status = MakeError(ErrorCode::kIoError, "closing '" + path.string() + "' failed: " + std::strerror(errno));
  }
  if (status.ok()) {
    fs::rename(tmp, path, ec);
    if (ec) status = MakeError(ErrorCode::kIoError, "cannot replace '" + path.string() + "': " + ec.message());
  }
  if (!status.ok()) fs::remove(tmp, ec);
  return status;
}

Status WriteFileAtomically(const std::filesystem::path& path, std::string_view content) {
  return WriteFileAtomically(path, [&](std::FILE* f) -> Status {
    if (std::fwrite(content.data(), 1, content.size(), f) != content.size()) {
      return MakeError(ErrorCode::kIoError, "writing '" + path.string() + "' failed: " + std::strerror(errno));
    }
    return Status::Ok();
  });
}

}  // namespace scanreg
