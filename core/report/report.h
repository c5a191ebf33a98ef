// The registration report: one self-contained HTML page (inline CSS, no scripts, no network)
// with PNG pictures beside it, from a saved project — summary and settings, the confusion-matrix
// heat map, the scan network, the per-link evidence, the per-scan poses and, with reference
// poses, the errors per scan (W fig. 6). `scanreg-cli report` and the GUI's File → Export report
// both call WriteReport.
#pragma once

#include <filesystem>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/io/project.h"

namespace scanreg::report {

// Picture files written beside index.html.
inline constexpr const char* kConfusionPng = "confusion.png";
inline constexpr const char* kNetworkPng = "network.png";
inline constexpr const char* kErrorsPng = "errors.png";

// Writes dir/index.html and its pictures (creating dir when missing; files of an earlier report
// are replaced atomically). Reads only the project (no scan files). Returns the path of
// index.html; an error names the folder or file and what to do (dir is a file, not writable).
Expected<std::filesystem::path> WriteReport(const io::Project& project, const std::filesystem::path& dir,
                                            ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg::report
