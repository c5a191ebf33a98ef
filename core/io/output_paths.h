// Outputs never replace inputs: every command checks the files it will write against the files it
// reads (the project file and its scans) before it starts the work.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/io/project.h"

namespace scanreg::io {

// The files a command on `project` reads: the project file and every scan file.
std::vector<std::filesystem::path> ProjectInputs(const Project& project);

// An error naming both files when `output` is one of `inputs` (the same path, or an existing file
// reached through another name or a link). `what` names the output in the message, e.g. "--out".
Status CheckNotAnInput(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs,
                       const std::string& what);

}  // namespace scanreg::io
