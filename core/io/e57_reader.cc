#include "core/io/e57_reader.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/io/e57_pages.h"
#include "core/io/e57_points.h"
#include "core/io/e57_xml.h"
#include "core/io/las_reader.h"
#include "core/io/organize_default.h"

namespace scanreg::io {

namespace {

constexpr double kMaxSide = 1e6;           // rows or columns
constexpr double kMaxCells = 5e8;          // rows * columns
constexpr double kMaxCellsPerPoint = 1e3;  // a grid far sparser than this is a corrupt index

struct OpenedE57 {
  e57::PagedReader file;
  std::vector<e57::ScanDesc> scans;
};

Expected<OpenedE57> OpenE57(const std::filesystem::path& path) {
  Expected<e57::PagedReader> file = e57::PagedReader::Open(path);
  if (!file) return file.error();
  std::string xml;
  if (Status s = file->ReadXml(&xml); !s) return s.error();
  Expected<std::vector<e57::ScanDesc>> scans = e57::ParseE57Xml(xml, path.string());
  if (!scans) return scans.error();
  return OpenedE57{std::move(*file), std::move(*scans)};
}

std::string ScanName(const e57::ScanDesc& scan, std::size_t index, std::size_t count,
                     const std::filesystem::path& path) {
  if (!scan.name.empty()) return scan.name;
  return count == 1 ? path.stem().string() : path.stem().string() + "_" + std::to_string(index + 1);
}

std::string Label(const e57::ScanDesc& scan, std::size_t index) {
  return "scan " + std::to_string(index + 1) + (scan.name.empty() ? "" : " ('" + scan.name + "')");
}

Expected<std::vector<std::size_t>> SelectScans(const std::vector<e57::ScanDesc>& scans, const E57ReadOptions& options,
                                               const std::filesystem::path& path) {
  std::vector<std::size_t> chosen;
  const bool all = options.indices.empty() && options.names.empty();
  for (int index : options.indices) {
    if (index < 0 || std::size_t(index) >= scans.size()) {
      return MakeError(ErrorCode::kNotFound, path.string() + ": no scan with index " + std::to_string(index) +
                                                 "; the file holds " + std::to_string(scans.size()) +
                                                 " scan(s), indexed from 0");
    }
  }
  for (const std::string& name : options.names) {
    bool found = false;
    for (std::size_t i = 0; i < scans.size(); ++i) found = found || ScanName(scans[i], i, scans.size(), path) == name;
    if (!found) {
      std::string names;
      for (std::size_t i = 0; i < scans.size() && i < 20; ++i)
        names += (i ? ", '" : "'") + ScanName(scans[i], i, scans.size(), path) + "'";
      if (scans.size() > 20) names += ", ...";
      return MakeError(ErrorCode::kNotFound, path.string() + ": no scan named '" + name + "'; the file holds " + names);
    }
  }
  for (std::size_t i = 0; i < scans.size(); ++i) {
    bool wanted = all;
    for (int index : options.indices) wanted = wanted || std::size_t(index) == i;
    for (const std::string& name : options.names) wanted = wanted || ScanName(scans[i], i, scans.size(), path) == name;
    if (wanted) chosen.push_back(i);
  }
  return chosen;
}

// Maps stored intensity to [0, 1]: the scan's intensityLimits, else the field's limits, else the
// range of the data.
std::pair<double, double> IntensityRange(const e57::ScanDesc& desc, const e57::PointRecords& records) {
  if (desc.intensity_limits) return *desc.intensity_limits;
  const int f = desc.FieldIndex("intensity");
  if (f >= 0) {
    if (auto limits = desc.fields[f].ValueLimits(); limits && limits->second > limits->first) return *limits;
  }
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  for (std::size_t i = 0; i < records.intensity.size(); ++i) {
    if (!records.valid[i]) continue;
    lo = std::min(lo, double(records.intensity[i]));
    hi = std::max(hi, double(records.intensity[i]));
  }
  return {lo, hi};
}

// Maps stored colour to 0..255: the scan's colorLimits, else the red field's limits, else 0..255
// (the limits may be absent; an 8-bit camera's values are then taken as they are).
std::pair<double, double> ColourRange(const e57::ScanDesc& desc) {
  if (desc.colour_limits) return *desc.colour_limits;
  const int f = desc.FieldIndex("colorRed");
  if (f >= 0) {
    if (auto limits = desc.fields[f].ValueLimits(); limits && limits->second > limits->first) return *limits;
  }
  return {0.0, 255.0};
}

Rgb StoredToRgb(const Eigen::Vector3f& stored, const std::pair<double, double>& range) {
  const double scale = 255.0 / (range.second - range.first);
  return ToRgb((stored[0] - range.first) * scale, (stored[1] - range.first) * scale, (stored[2] - range.first) * scale);
}

// A record's time in the scan's time base (TimeBase): GPS seconds - 1e9 from the acquisitionStart.
double PointTime(const e57::PointRecords& records, const e57::ScanDesc& desc, std::size_t i) {
  return desc.acquisition_start ? (*desc.acquisition_start - kAdjustedGpsOffset) + records.time[i] : records.time[i];
}

const char* TimeBase(const e57::ScanDesc& desc) { return desc.acquisition_start ? kAdjustedGpsTime : kE57ScanSeconds; }

Expected<Scan> GridScan(const e57::PointRecords& records, const e57::ScanDesc& desc, std::string name,
                        const std::string& where, const std::pair<double, double>& intensity_range) {
  std::int64_t row_min = std::numeric_limits<std::int64_t>::max(), row_max = std::numeric_limits<std::int64_t>::min();
  std::int64_t col_min = row_min, col_max = row_max;
  for (std::size_t i = 0; i < records.xyz.size(); ++i) {
    if (!records.valid[i]) continue;
    row_min = std::min<std::int64_t>(row_min, records.row[i]);
    row_max = std::max<std::int64_t>(row_max, records.row[i]);
    col_min = std::min<std::int64_t>(col_min, records.column[i]);
    col_max = std::max<std::int64_t>(col_max, records.column[i]);
  }
  if (desc.index_bounds) {
    const e57::IndexBounds& b = *desc.index_bounds;
    if (row_min < b.row_minimum || row_max > b.row_maximum || col_min < b.column_minimum ||
        col_max > b.column_maximum) {
      if (row_min <= row_max) {
        return MakeError(ErrorCode::kParseError, where +
                                                     ": a rowIndex/columnIndex lies outside the scan's indexBounds; "
                                                     "the file is damaged");
      }
    }
    row_min = b.row_minimum, row_max = b.row_maximum, col_min = b.column_minimum, col_max = b.column_maximum;
  }
  if (!desc.index_bounds && (row_min > row_max || col_min > col_max)) {  // no valid point and no bounds
    row_min = row_max = col_min = col_max = 0;
  }
  const double rows = double(row_max) - double(row_min) + 1, cols = double(col_max) - double(col_min) + 1;
  if (rows < 1 || cols < 1 || rows > kMaxSide || cols > kMaxSide || rows * cols > kMaxCells ||
      rows * cols > 1e6 + kMaxCellsPerPoint * double(records.xyz.size())) {
    return MakeError(ErrorCode::kParseError, where + ": impossible grid of " + std::to_string(std::int64_t(rows)) +
                                                 " rows x " + std::to_string(std::int64_t(cols)) + " columns for " +
                                                 std::to_string(records.xyz.size()) +
                                                 " points; the row/column indices are corrupt");
  }
  Scan scan(std::move(name), int(rows), int(cols));
  const auto colour_range = ColourRange(desc);
  if (!records.colour.empty()) scan.AddColour();
  if (!records.time.empty()) scan.AddTime();
  const double scale =
      intensity_range.second > intensity_range.first ? 1.0 / (intensity_range.second - intensity_range.first) : 0.0;
  for (std::size_t i = 0; i < records.xyz.size(); ++i) {
    if (!records.valid[i]) continue;
    const int r = int(records.row[i] - row_min), c = int(records.column[i] - col_min);
    const float refl = records.intensity.empty() ? 0.5f
                       : scale > 0.0             ? float((records.intensity[i] - intensity_range.first) * scale)
                                                 : 0.5f;
    if (scan.IsValid(r, c)) {  // the first point of a cell takes it; later returns stay as a list
      scan.list_points.push_back(records.xyz[i]);
      scan.list_reflectance.push_back(refl);
      if (scan.HasColour()) scan.list_colour.push_back(StoredToRgb(records.colour[i], colour_range));
      if (scan.HasTime()) scan.list_time.push_back(PointTime(records, desc, i));
      continue;
    }
    scan.Set(r, c, records.xyz[i], refl);
    if (scan.HasColour()) scan.colour[scan.Index(r, c)] = StoredToRgb(records.colour[i], colour_range);
    if (scan.HasTime()) scan.time[scan.Index(r, c)] = PointTime(records, desc, i);
  }
  EstimateAngularGrid(scan);
  return scan;
}

Expected<Scan> CloudScan(const e57::PointRecords& records, const e57::ScanDesc& desc, std::string name,
                         const std::string& where, const std::pair<double, double>& intensity_range) {
  std::vector<Eigen::Vector3f> points;
  std::vector<float> reflectance;
  std::vector<Rgb> colour;
  std::vector<double> time;
  const auto colour_range = ColourRange(desc);
  const double scale =
      intensity_range.second > intensity_range.first ? 1.0 / (intensity_range.second - intensity_range.first) : 0.0;
  for (std::size_t i = 0; i < records.xyz.size(); ++i) {
    if (!records.valid[i]) continue;
    points.push_back(records.xyz[i]);
    reflectance.push_back(records.intensity.empty() || scale == 0.0
                              ? 0.5f
                              : float((records.intensity[i] - intensity_range.first) * scale));
    if (!records.colour.empty()) colour.push_back(StoredToRgb(records.colour[i], colour_range));
    if (!records.time.empty()) time.push_back(PointTime(records, desc, i));
  }
  return OrganizeCloudByDensity(points, reflectance, std::move(name), where, colour, time);
}

}  // namespace

Expected<std::vector<E57ScanInfo>> ListE57Scans(const std::filesystem::path& path) {
  Expected<OpenedE57> opened = OpenE57(path);
  if (!opened) return opened.error();
  std::vector<E57ScanInfo> infos;
  for (std::size_t i = 0; i < opened->scans.size(); ++i) {
    const e57::ScanDesc& d = opened->scans[i];
    E57ScanInfo info;
    info.name = ScanName(d, i, opened->scans.size(), path);
    info.points = d.record_count;
    if (d.HasGrid() && d.index_bounds) {
      info.rows =
          int(std::clamp<std::int64_t>(d.index_bounds->row_maximum - d.index_bounds->row_minimum + 1, 0, 1 << 30));
      info.cols = int(
          std::clamp<std::int64_t>(d.index_bounds->column_maximum - d.index_bounds->column_minimum + 1, 0, 1 << 30));
    }
    info.has_intensity = d.FieldIndex("intensity") >= 0;
    info.has_pose = d.has_pose;
    infos.push_back(std::move(info));
  }
  return infos;
}

Expected<std::vector<Scan>> ReadE57(const std::filesystem::path& path, const E57ReadOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel) {
  Expected<OpenedE57> opened = OpenE57(path);
  if (!opened) return opened.error();
  const std::vector<e57::ScanDesc>& descs = opened->scans;
  if (descs.empty()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": the E57 file holds no 3D scan (data3D is empty)");
  }
  Expected<std::vector<std::size_t>> chosen = SelectScans(descs, options, path);
  if (!chosen) return chosen.error();
  std::vector<Scan> scans;
  for (std::size_t k = 0; k < chosen->size(); ++k) {
    const std::size_t i = (*chosen)[k];
    const e57::ScanDesc& desc = descs[i];
    const std::string label = Label(desc, i);
    SubProgress sub(progress, double(k) / double(chosen->size()), double(k + 1) / double(chosen->size()));
    Expected<e57::PointRecords> records = e57::ReadPoints(opened->file, desc, label, sub, cancel);
    if (!records) return records.error();
    const std::string where = path.string() + ": " + label;
    const auto intensity_range = IntensityRange(desc, *records);
    std::string name = ScanName(desc, i, descs.size(), path);
    Expected<Scan> scan = desc.HasGrid() ? GridScan(*records, desc, std::move(name), where, intensity_range)
                                         : CloudScan(*records, desc, std::move(name), where, intensity_range);
    if (!scan) return scan.error();
    scan->world_from_scan = desc.world_from_scan * Eigen::Translation3d(records->shift);
    if (scan->HasTime()) {
      scan->time_base = TimeBase(desc);
      if (Status v = scan->Validate(); !v)  // acquisitionStart + timeStamp can overflow
        return MakeError(ErrorCode::kParseError, where + ": " + v.error().message + " (acquisitionStart + timeStamp?); the file is damaged");
    }
    scans.push_back(std::move(*scan));
  }
  progress.Report(1.0, "reading " + path.filename().string());
  return scans;
}

}  // namespace scanreg::io
