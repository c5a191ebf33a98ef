// The readers the fuzz harness drives (issue 16): each target writes its seed files (valid inputs
// of its format, made by our writers or written by hand as other programs write them) and reads
// one input, checking what a reader promises beyond "no crash": an error is one printable line,
// and what it accepts is valid (finite points, consistent arrays, rigid poses).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace scanreg::fuzz {

struct FuzzTarget {
  std::string name;       // "ptx", "e57", ...
  std::string extension;  // of the input file the reader gets
  std::vector<std::string> seeds;
  // Reads the file; "" when the reader kept its promises (accepted valid data or gave a clean
  // error), else what it broke. `accepted` tells which of the two it was.
  std::function<std::string(const std::filesystem::path& file, bool* accepted)> read;
};

// Every target, with its seeds written through `work_dir` (created if missing).
std::vector<FuzzTarget> MakeTargets(const std::filesystem::path& work_dir);

}  // namespace scanreg::fuzz
