// Reading and writing scans by file extension: .ptx and .e57 (several scans), .ply and .pcd (one scan).
#pragma once

#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Extensions are matched case-insensitively. A scan with no valid point is read without error
// (check Scan::CountValid(); the policy is the caller's).
Expected<std::vector<Scan>> ReadScanFile(const std::filesystem::path& path, ProgressSink& progress,
                                         const CancelToken& cancel);

Status WriteScanFile(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                     const CancelToken& cancel);

// ".ptx, .e57, .ply, .pcd" — for messages and file dialogs.
const char* SupportedScanExtensions();

}  // namespace scanreg::io
