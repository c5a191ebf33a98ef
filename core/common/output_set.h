// Outputs that come as a set (issue 16, item 5): a command that writes several files (one cloud per
// scan, a report's page and images, a simulated project's scans) either completes the set or
// removes the files it created, and says so — a full disk or a bad scan halfway no longer leaves a
// set that looks complete. Files that existed before the command are left as they are: each was
// replaced atomically (AtomicFile), and deleting them would lose the user's earlier version.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg {

class OutputSet {
 public:
  OutputSet() = default;
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet();  // Abandon() unless Complete() was called

  // Call before `path` is written: a file that does not exist yet is removed if the set is abandoned.
  void Track(const std::filesystem::path& path);
  // The set is complete: nothing is removed.
  void Complete() { complete_ = true; }
  // Removes the files created so far; returns how many.
  int Abandon();
  // Abandon(), and `error` with what was removed appended ("...; removed the 3 new file(s) written
  // before the error"; files that existed before keep whatever this run wrote to them, and are counted).
  Error Failed(Error error);

 private:
  std::vector<std::filesystem::path> created_;
  int replaced_ = 0;
  bool complete_ = false;
};

}  // namespace scanreg
