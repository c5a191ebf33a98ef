// Leica PTX (ASCII) scans: read and write, several scans per file (SPEC §1).
//
// Per scan: columns, rows, scanner position (3 numbers), 3 scanner-axis rows, a 4x4 transform
// written as 4 rows holding the transpose of the column-vector matrix (rows 1-3: rotation
// columns with a trailing 0; row 4: "tx ty tz 1"), then rows*cols lines `x y z intensity [r g b]`,
// column-major (all rows of column 0 first). File row i of column c is Scan row i, column c.
// The header transform becomes Scan::world_from_scan; points stay in the scanner frame.
// An all-zero xyz is an empty cell. Reflectance = intensity as written (PTX: 0..1). A scan whose
// first point line holds r g b (0..255) has colour.
#pragma once

#include <filesystem>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// Scans are named after the file stem; "<stem>_1", "<stem>_2", ... when the file holds more than
// one. Angles are estimated with EstimateAngularGrid. Errors name the file and the 1-based line.
Expected<std::vector<Scan>> ReadPtx(const std::filesystem::path& path, ProgressSink& progress,
                                    const CancelToken& cancel);

// Writes `x y z intensity` lines, `x y z intensity r g b` for a scan with colour (empty cells as
// `0 0 0 0.5 [0 0 0]`), with the shortest text that reads back to the same float. Atomic: the target is replaced only when everything was written.
Status WritePtx(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                const CancelToken& cancel);

}  // namespace scanreg::io
