#include "core/pipeline/scan_previews.h"

#include <algorithm>
#include <cmath>

#include "core/pipeline/project_scans.h"

namespace scanreg::pipeline {

int PreviewStride(int rows, int cols, std::size_t max_cells) {
  max_cells = std::max<std::size_t>(1, max_cells);
  int stride = 1;
  const auto cells = [&](int s) {
    return static_cast<std::size_t>((rows + s - 1) / s) * static_cast<std::size_t>((cols + s - 1) / s);
  };
  while (cells(stride) > max_cells && stride < std::max(rows, cols)) ++stride;
  return stride;
}

ScanPreview MakePreview(Scan scan, std::size_t max_cells) {
  ScanPreview p;
  p.full_rows = scan.rows;
  p.full_cols = scan.cols;
  p.full_valid = scan.CountValid();
  p.stride = PreviewStride(scan.rows, scan.cols, max_cells);
  if (p.stride == 1) {
    p.scan = std::move(scan);
    return p;
  }
  const int s = p.stride;
  Scan& out = p.scan;
  out = Scan(scan.name, (scan.rows + s - 1) / s, (scan.cols + s - 1) / s);
  const bool reflectance = scan.reflectance.size() == scan.size();
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.cols; ++c) {
      const std::size_t from = scan.Index(r * s, c * s), to = out.Index(r, c);
      out.points[to] = scan.points[from];
      out.valid[to] = scan.valid[from];
      out.reflectance[to] = reflectance ? scan.reflectance[from] : 0.5f;
    }
  }
  if (!scan.angles.empty()) {
    for (int c = 0; c < out.cols; ++c) out.angles.azimuth.push_back(scan.angles.azimuth[c * s]);
    for (int r = 0; r < out.rows; ++r) out.angles.elevation.push_back(scan.angles.elevation[r * s]);
  }
  out.world_from_scan = scan.world_from_scan;
  out.reference_world_from_scan = scan.reference_world_from_scan;
  return p;
}

std::size_t PreviewCellsPerScan(std::size_t scans, std::size_t total) {
  return std::max<std::size_t>(10'000, total / std::max<std::size_t>(1, scans));
}

Expected<std::vector<ScanPreview>> LoadScanPreviews(const io::Project& project, std::size_t max_cells_per_scan,
                                                    ProgressSink& progress, const CancelToken& cancel,
                                                    std::vector<int> which) {
  if (which.empty())
    for (std::size_t i = 0; i < project.scans.size(); ++i) which.push_back(static_cast<int>(i));
  std::vector<ScanPreview> previews;
  previews.reserve(which.size());
  // A run of scans from the same file is read together (a file is parsed once, not once a scan).
  for (std::size_t k = 0; k < which.size();) {
    std::size_t end = k + 1;
    const auto path_of = [&](std::size_t j) {
      const int i = which[j];
      return i >= 0 && i < static_cast<int>(project.scans.size()) ? project.scans[i].path : std::filesystem::path();
    };
    while (end < which.size() && path_of(end) == path_of(k)) ++end;
    SubProgress sub(progress, double(k) / which.size(), double(end) / which.size());
    Expected<std::vector<Scan>> full =
        LoadProjectScans(project, sub, cancel, std::vector<int>(which.begin() + k, which.begin() + end));
    if (!full) return full.error();
    for (Scan& scan : *full) previews.push_back(MakePreview(std::move(scan), max_cells_per_scan));
    k = end;
  }
  progress.Report(1.0, "scans loaded");
  return previews;
}

}  // namespace scanreg::pipeline
