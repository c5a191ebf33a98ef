// Atomic file output: write a temporary file beside the target, flush and fsync it, then rename
// it over the target. A crash or a cancelled job never leaves a half-written file.
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string_view>

#include "core/common/expected.h"

namespace scanreg {

// Calls write(file) on a temporary file in the target's directory; on success renames it to
// path, on any error (or a write that returns an error) removes the temporary and returns it.
Status WriteFileAtomically(const std::filesystem::path& path, const std::function<Status(std::FILE*)>& write);

// Convenience: the whole content at once.
Status WriteFileAtomically(const std::filesystem::path& path, std::string_view content);

}  // namespace scanreg
