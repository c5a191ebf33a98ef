// Atomic file replacement: write a temporary file beside the target, flush and fsync it, then
// rename it over the target. Readers never see a half-written file; a failed write leaves the
// old target untouched. The temporary is hidden (".<name>.tmp-<pid>-<n>"); those of a process that
// was killed mid-write are removed when a file is next written into the same folder.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "core/common/expected.h"

namespace scanreg {

class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path target);
  ~AtomicFile();  // removes the temporary file unless committed
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  // Creates the temporary file (in the target's directory, so that rename is atomic).
  Status Open();
  // Buffered append.
  Status Write(std::string_view bytes);
  // For writers that open the file themselves (PCL): closes our handle; they then write to
  // temp_path() and Commit() fsyncs and renames what they wrote.
  Status CloseForExternalWriter();
  // Flushes, fsyncs, renames over the target and fsyncs the directory.
  Status Commit();

  const std::filesystem::path& temp_path() const { return temp_; }
  const std::filesystem::path& target() const { return target_; }

 private:
  Status Flush();
  Status Fail(const std::string& what);

  std::filesystem::path target_;
  std::filesystem::path temp_;
  int fd_ = -1;
  bool committed_ = false;
  std::string buffer_;
};

}  // namespace scanreg
