#include "core/pipeline/scan_previews.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>

#include "core/common/atomic_file.h"
#include "core/common/hash.h"
#include "core/common/log.h"
#include "core/io/scan_cache.h"
#include "core/io/text_parse.h"
#include "core/pipeline/project_scans.h"

namespace scanreg::pipeline {
namespace {

// A preview kept beside the binary scan cache, so that reopening a project reads previews (a few MB
// a scan) instead of whole scans: "<cache>/preview_<16 hex>.scan", the hex a hash of the source
// file's key, the scan's index in it and the cell budget. Bytes: a scan-cache entry of the preview
// (io::SerializeScanCache, checksummed) | i32 stride | i32 full rows | i32 full cols | u64 full valid
// | u64 the entry's size.
struct PreviewEntry {
  std::filesystem::path path;
  std::uint64_t key = 0;
};

std::optional<PreviewEntry> PreviewEntryOf(const io::Project& project, const io::ProjectScan& scan,
                                           std::size_t max_cells) {
  const std::filesystem::path dir = ProjectCacheDir(project);
  if (dir.empty()) return std::nullopt;
  Expected<std::uint64_t> source = io::MemoisedSourceFileKey(scan.path, dir);
  if (!source) return std::nullopt;  // the scan's reading names the problem
  Hasher h(0x9E7EULL);
  const std::uint64_t parts[3] = {*source, static_cast<std::uint64_t>(scan.index_in_file), max_cells};
  h.Add(reinterpret_cast<const char*>(parts), sizeof parts);
  char name[40];
  std::snprintf(name, sizeof name, "preview_%016llx.scan", static_cast<unsigned long long>(h.Digest()));
  return PreviewEntry{dir / name, h.Digest()};
}

constexpr std::size_t kTrailer = 3 * 4 + 8 + 8;

std::optional<ScanPreview> ReadPreview(const PreviewEntry& entry) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(entry.path, ec)) return std::nullopt;
  const auto corrupt = [&] {
    LogWarning(entry.path.string() + ": not a valid preview (truncated or corrupt); it is made again");
    return std::nullopt;
  };
  Expected<std::string> bytes = io::ReadWholeFile(entry.path);
  if (!bytes || bytes->size() < kTrailer) return corrupt();
  const char* tail = bytes->data() + bytes->size() - kTrailer;
  std::int32_t grid[3];
  std::uint64_t valid = 0, size = 0;
  std::memcpy(grid, tail, sizeof grid);
  std::memcpy(&valid, tail + 12, 8);
  std::memcpy(&size, tail + 20, 8);
  if (size != bytes->size() - kTrailer) return corrupt();
  bytes->resize(size);
  Expected<std::vector<Scan>> scans = io::ParseScanCache(*bytes, entry.key);
  if (!scans || scans->size() != 1 || grid[0] < 1) return corrupt();
  ScanPreview p;
  p.scan = std::move(scans->front());
  p.stride = grid[0];
  p.full_rows = grid[1];
  p.full_cols = grid[2];
  p.full_valid = valid;
  return p;
}

void WritePreview(const PreviewEntry& entry, const ScanPreview& p) {
  std::string bytes = io::SerializeScanCache({p.scan}, entry.key);
  const std::uint64_t size = bytes.size(), valid = p.full_valid;
  const std::int32_t grid[3] = {p.stride, p.full_rows, p.full_cols};
  bytes.append(reinterpret_cast<const char*>(grid), sizeof grid);
  bytes.append(reinterpret_cast<const char*>(&valid), 8);
  bytes.append(reinterpret_cast<const char*>(&size), 8);
  AtomicFile out(entry.path);
  Status s = out.Open();
  if (s) s = out.Write(bytes);
  if (s) s = out.Commit();
  if (!s) LogWarning("scan previews: cannot write " + entry.path.string() + ": " + s.error().message);
}

}  // namespace

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
  p.full_valid = scan.CountPoints();
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
  if (scan.HasColour()) {
    out.colour.resize(out.size());
    for (int r = 0; r < out.rows; ++r)
      for (int c = 0; c < out.cols; ++c) out.colour[out.Index(r, c)] = scan.colour[scan.Index(r * s, c * s)];
  }
  if (!scan.angles.empty()) {
    for (int c = 0; c < out.cols; ++c) out.angles.azimuth.push_back(scan.angles.azimuth[c * s]);
    for (int r = 0; r < out.rows; ++r) out.angles.elevation.push_back(scan.angles.elevation[r * s]);
  }
  // The points off the grid thinned as the grid is: one in stride^2.
  for (std::size_t k = 0; k < scan.list_points.size(); k += static_cast<std::size_t>(s) * s) {
    out.list_points.push_back(scan.list_points[k]);
    out.list_reflectance.push_back(scan.list_reflectance[k]);
    if (scan.HasColour()) out.list_colour.push_back(scan.list_colour[k]);
  }
  out.single_viewpoint = scan.single_viewpoint;
  out.grid_from_file = scan.grid_from_file;
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
  std::vector<std::optional<ScanPreview>> previews(which.size());
  std::vector<std::optional<PreviewEntry>> entries(which.size());
  std::vector<std::size_t> missing;  // positions in `which` not in the preview cache
  for (std::size_t k = 0; k < which.size(); ++k) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "loading scans cancelled");
    const int i = which[k];
    if (i >= 0 && i < static_cast<int>(project.scans.size()))
      entries[k] = PreviewEntryOf(project, project.scans[i], max_cells_per_scan);
    if (entries[k]) previews[k] = ReadPreview(*entries[k]);
    if (!previews[k]) missing.push_back(k);
  }
  // The others read in full, a run of scans from the same file together (a file is parsed once).
  for (std::size_t m = 0; m < missing.size();) {
    const auto path_of = [&](std::size_t j) {
      const int i = which[missing[j]];
      return i >= 0 && i < static_cast<int>(project.scans.size()) ? project.scans[i].path : std::filesystem::path();
    };
    std::size_t end = m + 1;
    while (end < missing.size() && path_of(end) == path_of(m)) ++end;
    SubProgress sub(progress, double(m) / missing.size(), double(end) / missing.size());
    std::vector<int> run;
    for (std::size_t j = m; j < end; ++j) run.push_back(which[missing[j]]);
    Expected<std::vector<Scan>> full = LoadProjectScans(project, sub, cancel, run);
    if (!full) return full.error();
    for (std::size_t j = m; j < end; ++j) {
      const std::size_t k = missing[j];
      previews[k] = MakePreview(std::move((*full)[j - m]), max_cells_per_scan);
      if (entries[k]) WritePreview(*entries[k], *previews[k]);
    }
    m = end;
  }
  std::vector<ScanPreview> out;
  out.reserve(which.size());
  for (std::size_t k = 0; k < which.size(); ++k) {
    ScanPreview& p = *previews[k];
    const io::ProjectScan& ps = project.scans[which[k]];  // named and posed as the project says
    p.scan.name = ps.name;
    p.scan.world_from_scan = ps.world_from_scan;
    p.scan.reference_world_from_scan = ps.reference_world_from_scan;
    out.push_back(std::move(p));
  }
  progress.Report(1.0, "scans loaded");
  return out;
}

}  // namespace scanreg::pipeline
