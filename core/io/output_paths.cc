#include "core/io/output_paths.h"

namespace scanreg::io {

std::vector<std::filesystem::path> ProjectInputs(const Project& project) {
  std::vector<std::filesystem::path> inputs;
  if (!project.file.empty()) inputs.push_back(project.file);
  for (const ProjectScan& s : project.scans) inputs.push_back(s.path);
  return inputs;
}

Status CheckNotAnInput(const std::filesystem::path& output, const std::vector<std::filesystem::path>& inputs,
                       const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path out = fs::absolute(output, ec).lexically_normal();
  for (const fs::path& input : inputs) {
    const fs::path in = fs::absolute(input, ec).lexically_normal();
    bool same = out == in;
    if (!same && fs::exists(out, ec) && fs::exists(in, ec)) same = fs::equivalent(out, in, ec);
    if (same) {
      return MakeError(ErrorCode::kInvalidArgument, what + " '" + output.string() + "' is the input file '" +
                                                        input.string() + "'; write to another file");
    }
  }
  return Status::Ok();
}

}  // namespace scanreg::io
