#include "core/io/ply.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/common/atomic_file.h"
#include "core/geometry/transform.h"
#include "core/io/organize_default.h"
#include "core/io/ply_header.h"
#include "core/io/text_parse.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "WritePly writes host floats as little-endian");

namespace scanreg::io {

namespace {

constexpr int kProgressSteps = 40;

// Yields the values of the body one by one, in file order, for ASCII and binary bodies alike.
class BodyCursor {
 public:
  BodyCursor(std::string_view text, const PlyHeader& header, const std::filesystem::path& path)
      : text_(text),
        format_(header.format),
        lines_(text, header.body_offset, header.body_line),
        pos_(header.body_offset),
        path_(path) {}

  // Starts the next element instance (ASCII: its line). `what` names it for errors.
  Status BeginInstance(const std::string& what) {
    what_ = &what;
    if (format_ != PlyFormat::kAscii) return Status::Ok();
    if (!lines_.Next(&line_)) {
      return MakeError(ErrorCode::kParseError, AtLine(path_, lines_.line_number() + 1) + "the file ends before " +
                                                   what + "; the file is truncated");
    }
    return Status::Ok();
  }
  bool Read(PlyType type, double* value, Status* status) {
    if (format_ == PlyFormat::kAscii) {
      const std::string_view token = NextToken(&line_);
      if (token.empty()) {
        *status = MakeError(ErrorCode::kParseError, AtLine(path_, lines_.line_number()) + *what_ +
                                                        " has fewer values than the header declares");
        return false;
      }
      const NumberParse p = ParseNumbers(token, value, 1);
      if (p.status == ParseStatus::kBadToken) {
        *status = MakeError(ErrorCode::kParseError, AtLine(path_, lines_.line_number()) + QuoteToken(token) + " in " +
                                                        *what_ + " is not a number");
        return false;
      }
      if (p.status == ParseStatus::kNonFinite) *value = std::numeric_limits<double>::quiet_NaN();
      return true;
    }
    const int size = PlyTypeSize(type);
    if (pos_ + size > text_.size()) {
      *status = MakeError(ErrorCode::kParseError,
                          path_.string() + ": the file ends inside " + *what_ + "; the file is truncated");
      return false;
    }
    unsigned char b[8];
    std::memcpy(b, text_.data() + pos_, size);
    pos_ += size;
    if (format_ == PlyFormat::kBinaryBigEndian) std::reverse(b, b + size);
    switch (type) {
      case PlyType::kInt8:
        *value = static_cast<std::int8_t>(b[0]);
        break;
      case PlyType::kUint8:
        *value = b[0];
        break;
      case PlyType::kInt16: {
        std::int16_t v;
        std::memcpy(&v, b, 2);
        *value = v;
        break;
      }
      case PlyType::kUint16: {
        std::uint16_t v;
        std::memcpy(&v, b, 2);
        *value = v;
        break;
      }
      case PlyType::kInt32: {
        std::int32_t v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kUint32: {
        std::uint32_t v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        *value = v;
        break;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        *value = v;
        break;
      }
    }
    return true;
  }

  // Skips a whole instance of an element we do not use.
  bool SkipInstance(const PlyElement& element, Status* status) {
    if (format_ == PlyFormat::kAscii) return true;  // BeginInstance consumed the line
    for (const PlyProperty& prop : element.properties) {
      double count = 1;
      if (prop.is_list && !Read(prop.count_type, &count, status)) return false;
      const std::size_t bytes = static_cast<std::size_t>(count) * PlyTypeSize(prop.type);
      if (pos_ + bytes > text_.size()) {
        *status = MakeError(ErrorCode::kParseError, path_.string() + ": the file ends inside element '" + element.name +
                                                        "'; the file is truncated");
        return false;
      }
      pos_ += bytes;
    }
    return true;
  }

  long line() const { return lines_.line_number(); }
  bool ascii() const { return format_ == PlyFormat::kAscii; }
  double fraction() const {
    return double(ascii() ? lines_.offset() : pos_) / double(std::max<std::size_t>(1, text_.size()));
  }

 private:
  std::string_view text_;
  PlyFormat format_;
  LineReader lines_;
  std::string_view line_;
  std::size_t pos_;
  const std::filesystem::path& path_;
  const std::string* what_ = nullptr;
};

float IntensityScale(PlyType type) {
  if (type == PlyType::kUint8) return 1.0f / 255.0f;
  if (type == PlyType::kUint16) return 1.0f / 65535.0f;
  return 1.0f;
}

// The vertex properties holding red, green and blue, in that order (all -1 when one is missing).
void ColourProperties(const PlyElement& vertex, int ic[3]) {
  static const char* const kNames[][3] = {
      {"red", "green", "blue"}, {"r", "g", "b"}, {"diffuse_red", "diffuse_green", "diffuse_blue"}};
  for (const auto& names : kNames) {
    for (int c = 0; c < 3; ++c) ic[c] = vertex.FindProperty(names[c]);
    if (ic[0] >= 0 && ic[1] >= 0 && ic[2] >= 0) return;
  }
  ic[0] = ic[1] = ic[2] = -1;
}

// To 0..255: 8-bit channels as they are, 16-bit ones / 257, floating point ones (0..1) x 255.
double ColourScale(PlyType type) {
  if (type == PlyType::kUint16) return 1.0 / 257.0;
  if (type == PlyType::kFloat32 || type == PlyType::kFloat64) return 255.0;
  return 1.0;
}

Expected<int> ObjInfoInt(const PlyHeader& header, const std::string& key, const std::filesystem::path& path) {
  auto it = header.obj_info.find(key);
  int v = 0;
  if (it == header.obj_info.end()) {
    return MakeError(ErrorCode::kParseError, path.string() + ": the file has a range_grid but no \"obj_info " + key +
                                                 "\" line, so the grid's shape is unknown");
  }
  auto [ptr, ec] = std::from_chars(it->second.data(), it->second.data() + it->second.size(), v);
  if (ec != std::errc() || v <= 0) {
    return MakeError(ErrorCode::kParseError, path.string() + ": \"obj_info " + key + "\" must be a positive integer");
  }
  return v;
}

}  // namespace

Expected<Scan> ReadPly(const std::filesystem::path& path, ProgressSink& progress, const CancelToken& cancel) {
  Expected<std::string> text = ReadWholeFile(path);
  if (!text) return text.error();
  Expected<PlyHeader> header = ParsePlyHeader(*text, path);
  if (!header) return header.error();

  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();
  if (auto it = header->obj_info.find("scanreg_world_from_scan"); it != header->obj_info.end()) {
    std::array<double, 16> m{};
    const NumberParse p = ParseNumbers(it->second, m.data(), 16);
    Eigen::Matrix3d raw, rotation;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) raw(r, c) = m[r * 4 + c];
    if (p.status != ParseStatus::kOk || p.count != 16 || !ProjectToRotation(raw, &rotation)) {
      return MakeError(ErrorCode::kParseError,
                       path.string() +
                           ": \"obj_info scanreg_world_from_scan\" must hold the 16 numbers of a rigid "
                           "4x4 matrix, row-major");
    }
    world_from_scan = IsometryFromRowMajor(m);
  }
  // scanreg's own PLY holds world coordinates (every reader places them); back to the scanner frame.
  const bool points_in_world = header->obj_info.count("scanreg_points_in_world") > 0;
  const Eigen::Isometry3d scan_from_world = world_from_scan.inverse();
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;
  std::vector<Rgb> colour;
  std::vector<double> time;
  std::vector<Eigen::Vector3f> sensor;
  std::vector<int> grid;  // vertex index per file cell, -1 = empty
  bool have_vertex = false, have_grid = false;
  long vertex_first_line = 0;
  std::size_t total = 0, done = 0;
  for (const PlyElement& e : header->elements) total += e.count;
  const std::size_t report_every = std::max<std::size_t>(1, total / kProgressSteps);
  const std::string stage = "reading " + path.filename().string();

  BodyCursor cursor(*text, *header, path);
  Status status;
  for (const PlyElement& element : header->elements) {
    const bool is_vertex = element.name == "vertex";
    const bool is_grid = element.name == "range_grid";
    int ix = -1, iy = -1, iz = -1, ii = -1, it = -1, ic[3] = {-1, -1, -1}, is[3] = {-1, -1, -1};
    if (is_vertex) {
      ix = element.FindProperty("x"), iy = element.FindProperty("y"), iz = element.FindProperty("z");
      if (ix < 0 || iy < 0 || iz < 0) {
        return MakeError(ErrorCode::kUnsupported, path.string() + ": the vertex element has no x, y and z properties");
      }
      for (const char* name : {"intensity", "scalar_intensity", "reflectance", "confidence"})
        if (ii < 0) ii = element.FindProperty(name);
      ColourProperties(element, ic);
      // Per-point time as scanreg, CloudCompare (a LAS's "GpsTime" scalar field) and PDAL name it.
      for (const char* name : {"gps_time", "GpsTime", "scalar_GpsTime", "gpstime", "time", "timestamp", "scalar_time"})
        if (it < 0) it = element.FindProperty(name);
      // Per-point sensor position as mobile-mapping sets (Paris-rue-Madame, iQmulus) and scanreg name
      // it; CloudCompare's PLY export prefixes its scalar fields with "scalar_".
      for (int a = 0; a < 3; ++a) {
        const std::string axis(1, "xyz"[a]);
        for (const std::string& name : {axis + "_origin", "scalar_" + axis + "_origin"})
          if (is[a] < 0) is[a] = element.FindProperty(name.c_str());
      }
      if (is[0] < 0 || is[1] < 0 || is[2] < 0) is[0] = is[1] = is[2] = -1;  // all three or none
      have_vertex = true;
      points.resize(element.count);
      if (is[0] >= 0) sensor.resize(element.count);
      if (ii >= 0) intensity.resize(element.count);
      if (it >= 0) time.resize(element.count);
      if (ic[0] >= 0) colour.resize(element.count);
      vertex_first_line = header->body_line + long(done);
    }
    if (is_grid) {
      if (element.properties.size() != 1 || !element.properties[0].is_list) {
        return MakeError(ErrorCode::kUnsupported,
                         path.string() + ": range_grid must have one list property (vertex_indices)");
      }
      have_grid = true;
      grid.assign(element.count, -1);
    }
    const float scale = ii >= 0 ? IntensityScale(element.properties[ii].type) : 1.0f;
    const double colour_scale = ic[0] >= 0 ? ColourScale(element.properties[ic[0]].type) : 1.0;
    double rgb[3] = {0, 0, 0};
    const std::string what = is_vertex ? "a vertex" : is_grid ? "a range_grid cell" : "element '" + element.name + "'";
    double v[4] = {0, 0, 0, 0.5}, t = 0, o[3] = {0, 0, 0};
    for (std::size_t k = 0; k < element.count; ++k, ++done) {
      if (done % report_every == 0) {
        if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, path.string() + ": cancelled");
        progress.Report(cursor.fraction(), stage);
      }
      if (status = cursor.BeginInstance(what); !status) return status.error();
      if (!is_vertex && !is_grid) {
        if (!cursor.SkipInstance(element, &status)) return status.error();
        continue;
      }
      if (is_grid) {
        const PlyProperty& prop = element.properties[0];
        double count = 0, index = -1;
        if (!cursor.Read(prop.count_type, &count, &status)) return status.error();
        for (int j = 0; j < static_cast<int>(count); ++j) {
          double item = 0;
          if (!cursor.Read(prop.type, &item, &status)) return status.error();
          if (j == 0) index = item;  // several returns per cell: the first takes it, the others stay as a list
        }
        if (count >= 1) {
          if (!(index >= 0 && index < double(points.size()))) {
            return MakeError(ErrorCode::kParseError,
                             (cursor.ascii() ? AtLine(path, cursor.line()) : path.string() + ": ") +
                                 "range_grid cell " + std::to_string(k) + " refers to vertex " +
                                 std::to_string(static_cast<long long>(index)) + ", but there are " +
                                 std::to_string(points.size()) + " vertices (the vertex element must come first)");
          }
          grid[k] = static_cast<int>(index);
        }
        continue;
      }
      for (int p = 0; p < static_cast<int>(element.properties.size()); ++p) {
        const PlyProperty& prop = element.properties[p];
        double value = 0, count = 1;
        if (prop.is_list && !cursor.Read(prop.count_type, &count, &status)) return status.error();
        for (int j = 0; j < static_cast<int>(count); ++j)
          if (!cursor.Read(prop.type, &value, &status)) return status.error();
        if (p == ix)
          v[0] = value;
        else if (p == iy)
          v[1] = value;
        else if (p == iz)
          v[2] = value;
        else if (p == ii)
          v[3] = value * scale;
        else if (p == it)
          t = value;
        else if (p == is[0] || p == is[1] || p == is[2])
          o[p == is[0] ? 0 : p == is[1] ? 1 : 2] = value;
        else if (p == ic[0] || p == ic[1] || p == ic[2])
          rgb[p == ic[0] ? 0 : p == ic[1] ? 1 : 2] = value * colour_scale;
      }
      const Eigen::Vector3d p(v[0], v[1], v[2]);
      points[k] = (points_in_world ? scan_from_world * p : p).cast<float>();
      if (ii >= 0) intensity[k] = float(v[3]);
      if (ic[0] >= 0) colour[k] = ToRgb(rgb[0], rgb[1], rgb[2]);
      if (it >= 0) time[k] = t;
      if (is[0] >= 0) {
        const Eigen::Vector3d origin(o[0], o[1], o[2]);
        sensor[k] = (points_in_world ? scan_from_world * origin : origin).cast<float>();
      }
    }
  }
  if (!have_vertex) return MakeError(ErrorCode::kUnsupported, path.string() + ": the PLY file has no vertex element");

  // NaN/inf are rejected where they would become valid cells.
  auto check_finite = [&](std::size_t k) -> Status {
    if (points[k].allFinite() && (intensity.empty() || std::isfinite(intensity[k])) &&
        (time.empty() || std::isfinite(time[k])) && (sensor.empty() || sensor[k].allFinite()))
      return Status::Ok();
    const std::string where =
        header->format == PlyFormat::kAscii ? AtLine(path, vertex_first_line + long(k)) : path.string() + ": ";
    return MakeError(ErrorCode::kParseError, where + "vertex " + std::to_string(k) +
                                                 " has a NaN or infinite value; remove it or leave its cell empty");
  };

  const std::string name = path.stem().string();
  Scan scan;
  if (have_grid) {
    Expected<int> cols = ObjInfoInt(*header, "num_cols", path);
    if (!cols) return cols.error();
    Expected<int> rows = ObjInfoInt(*header, "num_rows", path);
    if (!rows) return rows.error();
    if (static_cast<std::size_t>(*rows) * static_cast<std::size_t>(*cols) != grid.size()) {
      return MakeError(ErrorCode::kParseError, path.string() + ": range_grid has " + std::to_string(grid.size()) +
                                                   " cells but obj_info says " + std::to_string(*rows) + " rows x " +
                                                   std::to_string(*cols) + " columns");
    }
    scan = Scan(name, *rows, *cols);
    if (!colour.empty()) scan.AddColour();
    if (!time.empty()) scan.AddTime();
    if (!sensor.empty()) scan.AddSensor();
    for (int fr = 0; fr < *rows; ++fr) {
      for (int c = 0; c < *cols; ++c) {
        const int k = grid[static_cast<std::size_t>(fr) * *cols + c];
        if (k < 0) continue;
        if (Status s = check_finite(k); !s) return s.error();
        if (points[k].isZero()) continue;
        scan.Set(*rows - 1 - fr, c, points[k], intensity.empty() ? 0.5f : intensity[k]);
        if (!colour.empty()) scan.colour[scan.Index(*rows - 1 - fr, c)] = colour[k];
        if (!time.empty()) scan.time[scan.Index(*rows - 1 - fr, c)] = time[k];
        if (!sensor.empty()) scan.sensor[scan.Index(*rows - 1 - fr, c)] = sensor[k];
      }
    }
    // Vertices no cell takes (later returns of a cell, points without a cell) stay as a list.
    std::vector<std::uint8_t> in_grid(points.size(), 0);
    for (int k : grid)
      if (k >= 0) in_grid[k] = 1;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (in_grid[k] || !points[k].allFinite() || points[k].isZero()) continue;
      if (!intensity.empty() && !std::isfinite(intensity[k])) continue;
      if (!time.empty() && !std::isfinite(time[k])) continue;
      if (!sensor.empty() && !sensor[k].allFinite()) continue;
      scan.list_points.push_back(points[k]);
      scan.list_reflectance.push_back(intensity.empty() ? 0.5f : intensity[k]);
      if (!colour.empty()) scan.list_colour.push_back(colour[k]);
      if (!time.empty()) scan.list_time.push_back(time[k]);
      if (!sensor.empty()) scan.list_sensor.push_back(sensor[k]);
    }
    if (header->obj_info.count("scanreg_angular_grid")) EstimateAngularGrid(scan);
    if (SensorsSpread(sensor)) scan.single_viewpoint = false;  // a grid of points seen from several places
  } else {
    for (std::size_t k = 0; k < points.size(); ++k)
      if (Status s = check_finite(k); !s) return s.error();
    Expected<Scan> organized = OrganizeCloudByDensity(points, intensity, name, path.string(), colour, time, sensor);
    if (!organized) return organized.error();
    scan = std::move(*organized);
  }
  scan.world_from_scan = world_from_scan;
  if (auto base = header->obj_info.find("scanreg_time_base"); base != header->obj_info.end() && scan.HasTime())
    scan.time_base = base->second;
  progress.Report(1.0, stage);
  return scan;
}

Status WritePly(const std::filesystem::path& path, const Scan& scan, ProgressSink& progress,
                const CancelToken& cancel) {
  if (Status s = scan.Validate(); !s) return s;
  const std::size_t n_valid = scan.CountValid();
  if (n_valid + scan.list_points.size() > std::size_t(std::numeric_limits<std::int32_t>::max())) {
    return MakeError(ErrorCode::kInvalidArgument,
                     path.string() + ": more than 2^31 points do not fit one PLY range grid");
  }
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment written by scanreg: x y z in world coordinates (metres); "
      "scanreg_world_from_scan is the scanner's pose\n";
  // Points off the grid: every point as a plain list (readers that honour a range_grid, PCL's, drop
  // the vertices no cell names); the grid is made again when the file is read.
  const bool grid = scan.list_points.empty();
  if (grid) {
    header += "obj_info num_cols " + std::to_string(scan.cols) + "\n";
    header += "obj_info num_rows " + std::to_string(scan.rows) + "\n";
  }
  header += "obj_info scanreg_world_from_scan";
  char buf[64];
  for (double v : RowMajorFromIsometry(scan.world_from_scan)) {
    char* e = AppendNumber(buf, v);
    header += ' ';
    header.append(buf, e);
  }
  header += "\n";
  if (grid && !scan.angles.empty()) header += "obj_info scanreg_angular_grid 1\n";
  header += "obj_info scanreg_points_in_world 1\n";
  if (scan.HasTime() && !scan.time_base.empty()) header += "obj_info scanreg_time_base " + scan.time_base + "\n";
  header += "element vertex " + std::to_string(n_valid + scan.list_points.size()) +
            "\nproperty double x\nproperty double y\nproperty double z\nproperty float intensity\n";
  if (scan.HasColour()) header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  // CloudCompare's name: its PLY import reads the time as the "GpsTime" scalar field its LAS import makes.
  if (scan.HasTime()) header += "property double scalar_GpsTime\n";
  // Where each point was measured from, in world coordinates like the points; CloudCompare's silent
  // import reads "scalar_" properties as the scalar fields x_origin, y_origin, z_origin.
  if (scan.HasSensor())
    header += "property double scalar_x_origin\nproperty double scalar_y_origin\nproperty double scalar_z_origin\n";
  if (grid)
    header += "element range_grid " + std::to_string(scan.size()) + "\nproperty list uchar int vertex_indices\n";
  header += "end_header\n";

  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.Write(header); !s) return s;
  const std::string stage = "writing " + path.filename().string();
  // Vertices in Stanford order (file row 0 = bottom = Scan row rows-1), so indices ascend.
  std::string chunk;
  std::vector<std::int32_t> index(scan.size(), -1);
  std::int32_t next = 0;
  for (int fr = 0; fr < scan.rows; ++fr) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, path.string() + ": writing cancelled");
    if (fr % std::max(1, scan.rows / kProgressSteps) == 0) progress.Report(0.5 * fr / scan.rows, stage);
    const int r = scan.rows - 1 - fr;
    for (int c = 0; c < scan.cols; ++c) {
      const std::size_t i = scan.Index(r, c);
      if (!scan.valid[i]) continue;
      const Eigen::Vector3d p = scan.world_from_scan * scan.points[i].cast<double>();
      chunk.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
      chunk.append(reinterpret_cast<const char*>(&scan.reflectance[i]), sizeof(float));
      if (scan.HasColour()) chunk.append(reinterpret_cast<const char*>(scan.colour[i].data()), 3);
      if (scan.HasTime()) chunk.append(reinterpret_cast<const char*>(&scan.time[i]), sizeof(double));
      if (scan.HasSensor()) {
        const Eigen::Vector3d o = scan.world_from_scan * scan.sensor[i].cast<double>();
        chunk.append(reinterpret_cast<const char*>(o.data()), 3 * sizeof(double));
      }
      index[static_cast<std::size_t>(fr) * scan.cols + c] = next++;
    }
    if (chunk.size() > (1 << 20)) {
      if (Status s = file.Write(chunk); !s) return s;
      chunk.clear();
    }
  }
  for (std::size_t k = 0; k < scan.list_points.size(); ++k) {  // the points off the grid, after its own
    const Eigen::Vector3d p = scan.world_from_scan * scan.list_points[k].cast<double>();
    chunk.append(reinterpret_cast<const char*>(p.data()), 3 * sizeof(double));
    chunk.append(reinterpret_cast<const char*>(&scan.list_reflectance[k]), sizeof(float));
    if (scan.HasColour()) chunk.append(reinterpret_cast<const char*>(scan.list_colour[k].data()), 3);
    if (scan.HasTime()) chunk.append(reinterpret_cast<const char*>(&scan.list_time[k]), sizeof(double));
    if (scan.HasSensor()) {
      const Eigen::Vector3d o = scan.world_from_scan * scan.list_sensor[k].cast<double>();
      chunk.append(reinterpret_cast<const char*>(o.data()), 3 * sizeof(double));
    }
    if (chunk.size() > (1 << 20)) {
      if (Status s = file.Write(chunk); !s) return s;
      chunk.clear();
    }
  }
  for (std::size_t k = 0; grid && k < index.size(); ++k) {
    if (index[k] < 0) {
      chunk += '\0';
    } else {
      chunk += '\1';
      chunk.append(reinterpret_cast<const char*>(&index[k]), 4);
    }
    if (chunk.size() > (1 << 20)) {
      if (Status s = file.Write(chunk); !s) return s;
      chunk.clear();
      progress.Report(0.5 + 0.5 * double(k) / double(index.size()), stage);
    }
  }
  if (Status s = file.Write(chunk); !s) return s;
  if (Status s = file.Commit(); !s) return s;
  progress.Report(1.0, stage);
  return Status::Ok();
}

}  // namespace scanreg::io
