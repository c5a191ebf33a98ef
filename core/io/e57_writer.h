// Writing E57 (ASTM E2807) files that keep what registration needs: every scan with its full
// double pose (rotation quaternion + translation), its grid (rowIndex/columnIndex with
// indexBounds), its reflectance (intensity with intensityLimits 0..1) and its colour when it has
// one (colorRed/Green/Blue, 8-bit Integers, colorLimits 0..255). A scan with points off
// its grid (list_points) is written unstructured — every point, no rowIndex/columnIndex — since an
// E57 scan's records are either all indexed or none.
//
// Encoding: only valid cells are stored. cartesianX/Y/Z and intensity are Float single: the
// Scan's own float values, so a round trip is exact and no bounds or scale must be chosen
// (ScaledInteger at 0.1 mm would save ~30% but round every point). rowIndex/columnIndex are
// bit-packed Integers. Pages carry CRC-32C; the file is replaced atomically.
#pragma once

#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

Status WriteE57(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                const CancelToken& cancel);

}  // namespace scanreg::io
