// What the desktop keeps of each scan (issue 13 item 1): a preview on the scan's own grid — every
// stride-th row and column — sized so that all previews together stay within a global cell budget,
// plus the full scan's grid and point count. The views draw previews; a job that needs the points
// (registration, refinement, merge, a dialog that picks cells) reads the full scan from its file
// (the binary scan cache) through a ScanStore, so the desktop's memory no longer grows with the
// project's resolution: 100 stations of 10 M points hold 16 M preview cells, not 1 G.
#pragma once

#include <cstddef>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"

namespace scanreg::pipeline {

// Cells every preview of a project holds together (17 bytes each: about 270 MB). A project whose
// scans fit in it keeps them whole (stride 1).
constexpr std::size_t kPreviewCells = 16'000'000;

struct ScanPreview {
  Scan scan;               // rows 0, stride, 2 stride… of the scan; columns likewise; one list point in stride^2; named and posed as it
  int stride = 1;          // 1: the full scan
  int full_rows = 0;       // the full scan's grid
  int full_cols = 0;
  std::size_t full_valid = 0;  // the full scan's points (its grid's and its list's)
};

// The smallest stride whose preview of a rows x cols grid holds at most max_cells cells (at least 1).
int PreviewStride(int rows, int cols, std::size_t max_cells);
// The preview of `scan` with at most max_cells cells (the scan itself, moved, when it fits).
ScanPreview MakePreview(Scan scan, std::size_t max_cells);
// Cells one preview may hold in a project of `scans` scans (`total` shared, at least 10 000).
std::size_t PreviewCellsPerScan(std::size_t scans, std::size_t total = kPreviewCells);

// The project's previews, max_cells_per_scan cells at most each: from the preview cache beside
// the binary scan cache (keyed by the source file's content, the scan and the budget; a corrupt
// entry is made again with a warning), else read in full one at a time (LoadProjectScans: at most
// one file's scans in memory at once) and stored there. which: only these scans (by
// index, in this order); empty: all. Errors as LoadProjectScans's (naming the scan and its file).
Expected<std::vector<ScanPreview>> LoadScanPreviews(const io::Project& project, std::size_t max_cells_per_scan,
                                                    ProgressSink& progress, const CancelToken& cancel,
                                                    std::vector<int> which = {});

}  // namespace scanreg::pipeline
