#include "core/io/e57_writer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <pugixml.hpp>
#include <random>
#include <sstream>

#include "core/common/atomic_file.h"
#include "core/common/log.h"
#include "core/io/e57_bitpack.h"
#include "core/io/e57_pages.h"
#include "core/io/e57_points.h"
#include "core/io/e57_reader.h"
#include "core/io/las_reader.h"
#include "core/io/text_parse.h"

namespace scanreg::io {

namespace {

constexpr std::size_t kRecordsPerPacket = 2048;  // a multiple of 8: every packet ends on a byte
constexpr std::size_t kPacketsPerReport = 25;    // progress every ~51k points
constexpr double kGpsEpochUnix = 315964800.0;    // 1980-01-06 in Unix seconds
constexpr double kGpsLeapSeconds = 18.0;

// Where each written scan's points went, for the XML.
struct WrittenScan {
  std::uint64_t section_offset = 0;  // physical
  std::uint64_t records = 0;
  bool structured = true;  // rowIndex/columnIndex written: the scan has no point off its grid
  bool colour = false;     // colorRed, colorGreen, colorBlue written (8 bits each)
  bool time = false;       // timeStamp written (double)
  // The acquisitionStart (GPS seconds) the timeStamps count from: a whole second at or before the
  // first time, when the scan's times are GPS times; none otherwise (the times as they are).
  std::optional<double> acquisition_start;
  int row_bits = 0, col_bits = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
  double intensity_lo = 0.0, intensity_hi = 1.0;
};

// x, y, z, intensity, then colorRed, colorGreen, colorBlue with colour, timeStamp with time, then
// rowIndex, columnIndex when structured.
int ValueStreams(const WrittenScan& info) { return 4 + (info.colour ? 3 : 0) + (info.time ? 1 : 0); }
int Streams(const WrittenScan& info) { return ValueStreams(info) + (info.structured ? 2 : 0); }

// A point's timeStamp: its time from the acquisitionStart.
double TimeStamp(double time, const WrittenScan& info) {
  return info.acquisition_start ? time - (*info.acquisition_start - kAdjustedGpsOffset) : time;
}

std::uint64_t PacketLength(std::size_t records, const WrittenScan& info) {
  const std::uint64_t index_bytes =
      info.structured ? (records * info.row_bits + 7) / 8 + (records * info.col_bits + 7) / 8 : 0;
  const std::uint64_t bytes = 6 + 2 * Streams(info) + 4 * 4 * records + (info.colour ? 3 * records : 0) +
                              (info.time ? 8 * records : 0) + index_bytes;
  return (bytes + 3) / 4 * 4;
}

void PutLe(std::string& out, std::uint64_t v, int bytes) {
  char b[8];
  e57::StoreLe<std::uint64_t>(b, v);
  out.append(b, bytes);
}

void PutFloat(std::string& out, float v) {
  char b[4];
  std::memcpy(b, &v, 4);
  out.append(b, 4);
}

Status WriteScanPoints(e57::PagedWriter& w, const Scan& scan, WrittenScan* info, std::size_t* done, std::size_t total,
                       const std::string& target, ProgressSink& progress, const CancelToken& cancel) {
  std::vector<std::size_t> cells;
  cells.reserve(scan.CountValid());
  for (std::size_t i = 0; i < scan.size(); ++i)
    if (scan.valid[i]) cells.push_back(i);
  info->structured = scan.list_points.empty();
  info->colour = scan.HasColour();
  info->time = scan.HasTime();
  if (info->time && scan.time_base == kAdjustedGpsTime) {
    double first = std::numeric_limits<double>::infinity();
    for (std::size_t i : cells) first = std::min(first, scan.time[i]);
    for (double t : scan.list_time) first = std::min(first, t);
    if (std::isfinite(first)) info->acquisition_start = std::floor(first) + kAdjustedGpsOffset;
  }
  info->records = cells.size() + scan.list_points.size();
  info->row_bits = e57::BitWidth(0, scan.rows - 1);
  info->col_bits = e57::BitWidth(0, scan.cols - 1);
  std::uint64_t section_length = e57::kSectionHeaderSize;
  for (std::size_t b = 0; b < info->records; b += kRecordsPerPacket) {
    section_length += PacketLength(std::min<std::size_t>(kRecordsPerPacket, info->records - b), *info);
  }

  if (Status s = w.Align(8); !s) return s;
  info->section_offset = w.physical_offset();
  std::string header;
  header.push_back(static_cast<char>(e57::kCompressedVectorSection));
  header.append(7, '\0');
  PutLe(header, section_length, 8);
  PutLe(header, e57::PhysicalFromLogical(w.logical_size() + e57::kSectionHeaderSize), 8);
  PutLe(header, 0, 8);  // no index packets
  if (Status s = w.Append(header); !s) return s;

  float ilo = 0.0f, ihi = 1.0f;
  info->lo = Eigen::Vector3d::Constant(info->records == 0 ? 0.0 : 1e300);
  info->hi = Eigen::Vector3d::Constant(info->records == 0 ? 0.0 : -1e300);
  std::string streams[8], packet;  // x y z intensity, red green blue, time: as ValueStreams orders them
  const int value_streams = ValueStreams(*info);
  for (std::size_t b = 0; b < info->records; b += kRecordsPerPacket) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, target + ": writing cancelled");
    if ((b / kRecordsPerPacket) % kPacketsPerReport == 0) {
      progress.Report(double(*done) / double(std::max<std::size_t>(1, total)), "writing " + scan.name);
    }
    const std::size_t n = std::min<std::size_t>(kRecordsPerPacket, info->records - b);
    e57::BitWriter rows, cols;
    for (std::string& s : streams) s.clear();
    for (std::size_t k = b; k < b + n; ++k) {  // the grid's points, then the list's
      const bool on_grid = k < cells.size();
      const Eigen::Vector3f& p = on_grid ? scan.points[cells[k]] : scan.list_points[k - cells.size()];
      const float refl = on_grid ? scan.reflectance[cells[k]] : scan.list_reflectance[k - cells.size()];
      for (int d = 0; d < 3; ++d) PutFloat(streams[d], p[d]);
      PutFloat(streams[3], refl);
      if (info->colour) {
        const Rgb& c = on_grid ? scan.colour[cells[k]] : scan.list_colour[k - cells.size()];
        for (int ch = 0; ch < 3; ++ch) streams[4 + ch].push_back(static_cast<char>(c[ch]));
      }
      if (info->time) {
        const double t = TimeStamp(on_grid ? scan.time[cells[k]] : scan.list_time[k - cells.size()], *info);
        char bytes[8];
        std::memcpy(bytes, &t, 8);
        streams[info->colour ? 7 : 4].append(bytes, 8);
      }
      ilo = std::min(ilo, refl), ihi = std::max(ihi, refl);
      info->lo = info->lo.cwiseMin(p.cast<double>()), info->hi = info->hi.cwiseMax(p.cast<double>());
      if (!info->structured) continue;
      rows.Write(std::uint64_t(cells[k] / scan.cols), info->row_bits);
      cols.Write(std::uint64_t(cells[k] % scan.cols), info->col_bits);
    }
    const std::string row_bytes = rows.Take(true), col_bytes = cols.Take(true);
    const std::uint64_t length = PacketLength(n, *info);
    packet.clear();
    packet.push_back(static_cast<char>(e57::kDataPacket));
    packet.push_back('\0');
    PutLe(packet, length - 1, 2);
    PutLe(packet, Streams(*info), 2);
    for (int v = 0; v < value_streams; ++v) PutLe(packet, streams[v].size(), 2);
    if (info->structured) {
      PutLe(packet, row_bytes.size(), 2);
      PutLe(packet, col_bytes.size(), 2);
    }
    for (int v = 0; v < value_streams; ++v) packet += streams[v];
    packet += row_bytes;
    packet += col_bytes;
    packet.resize(length, '\0');
    if (Status s = w.Append(packet); !s) return s;
    *done += n;
  }
  info->intensity_lo = ilo, info->intensity_hi = ihi;
  return Status::Ok();
}

std::string Guid(std::mt19937_64& rng) {
  const std::uint64_t a = rng(), b = rng();
  char buf[48];
  std::snprintf(buf, sizeof(buf), "{%08X-%04X-%04X-%04X-%012llX}", unsigned(a >> 32), unsigned((a >> 16) & 0xFFFF),
                unsigned(0x4000 | (a & 0x0FFF)), unsigned(0x8000 | ((b >> 48) & 0x3FFF)),
                static_cast<unsigned long long>(b & 0xFFFFFFFFFFFFull));
  return buf;
}

std::string Number(double v) {
  char buf[40];
  return std::string(buf, AppendNumber(buf, v));
}

pugi::xml_node Element(pugi::xml_node parent, const char* name, const char* type) {
  pugi::xml_node node = parent.append_child(name);
  node.append_attribute("type") = type;
  return node;
}

void StringElement(pugi::xml_node parent, const char* name, const std::string& value) {
  Element(parent, name, "String").append_child(pugi::node_pcdata).set_value(value.c_str());
}

void FloatElement(pugi::xml_node parent, const char* name, double value) {
  Element(parent, name, "Float").append_child(pugi::node_pcdata).set_value(Number(value).c_str());
}

void IntegerElement(pugi::xml_node parent, const char* name, long long value) {
  Element(parent, name, "Integer").append_child(pugi::node_pcdata).set_value(std::to_string(value).c_str());
}

void PrototypeInteger(pugi::xml_node prototype, const char* name, long long maximum) {
  pugi::xml_node node = Element(prototype, name, "Integer");
  node.append_attribute("minimum") = "0";
  node.append_attribute("maximum") = std::to_string(maximum).c_str();
}

void ScanXml(pugi::xml_node data3d, const Scan& scan, const WrittenScan& info, std::mt19937_64& rng) {
  pugi::xml_node child = Element(data3d, "vectorChild", "Structure");
  StringElement(child, "guid", Guid(rng));
  StringElement(child, "name", scan.name);
  const Eigen::Quaterniond q(scan.world_from_scan.linear());
  const Eigen::Vector3d t = scan.world_from_scan.translation();
  pugi::xml_node pose = Element(child, "pose", "Structure");
  pugi::xml_node rotation = Element(pose, "rotation", "Structure");
  FloatElement(rotation, "w", q.w()), FloatElement(rotation, "x", q.x());
  FloatElement(rotation, "y", q.y()), FloatElement(rotation, "z", q.z());
  pugi::xml_node translation = Element(pose, "translation", "Structure");
  FloatElement(translation, "x", t.x()), FloatElement(translation, "y", t.y()), FloatElement(translation, "z", t.z());
  if (info.structured) {
    pugi::xml_node bounds = Element(child, "indexBounds", "Structure");
    IntegerElement(bounds, "rowMinimum", 0), IntegerElement(bounds, "rowMaximum", scan.rows - 1);
    IntegerElement(bounds, "columnMinimum", 0), IntegerElement(bounds, "columnMaximum", scan.cols - 1);
    IntegerElement(bounds, "returnMinimum", 0), IntegerElement(bounds, "returnMaximum", 0);
  }
  pugi::xml_node limits = Element(child, "intensityLimits", "Structure");
  FloatElement(limits, "intensityMinimum", info.intensity_lo);
  FloatElement(limits, "intensityMaximum", info.intensity_hi);
  if (info.colour) {
    pugi::xml_node colour = Element(child, "colorLimits", "Structure");
    for (const char* name : {"colorRed", "colorGreen", "colorBlue"}) {
      IntegerElement(colour, (std::string(name) + "Minimum").c_str(), 0);
      IntegerElement(colour, (std::string(name) + "Maximum").c_str(), 255);
    }
  }
  if (info.acquisition_start) {
    pugi::xml_node start = Element(child, "acquisitionStart", "Structure");
    FloatElement(start, "dateTimeValue", *info.acquisition_start);
    IntegerElement(start, "isAtomicClockReferenced", 0);
  }
  pugi::xml_node box = Element(child, "cartesianBounds", "Structure");
  const char* names[3][2] = {{"xMinimum", "xMaximum"}, {"yMinimum", "yMaximum"}, {"zMinimum", "zMaximum"}};
  for (int d = 0; d < 3; ++d) FloatElement(box, names[d][0], info.lo[d]), FloatElement(box, names[d][1], info.hi[d]);
  pugi::xml_node points = Element(child, "points", "CompressedVector");
  points.append_attribute("fileOffset") = std::to_string(info.section_offset).c_str();
  points.append_attribute("recordCount") = std::to_string(info.records).c_str();
  pugi::xml_node prototype = Element(points, "prototype", "Structure");
  for (const char* name : {"cartesianX", "cartesianY", "cartesianZ", "intensity"}) {
    Element(prototype, name, "Float").append_attribute("precision") = "single";
  }
  for (const char* name : {"colorRed", "colorGreen", "colorBlue"})
    if (info.colour) PrototypeInteger(prototype, name, 255);
  if (info.time) Element(prototype, "timeStamp", "Float");  // double precision
  if (info.structured) {
    PrototypeInteger(prototype, "rowIndex", scan.rows - 1);
    PrototypeInteger(prototype, "columnIndex", scan.cols - 1);
  }
  Element(points, "codecs", "Vector").append_attribute("allowHeterogeneousChildren") = "1";
}

std::string DocumentXml(const std::vector<Scan>& scans, const std::vector<WrittenScan>& written) {
  std::mt19937_64 rng(std::random_device{}());
  pugi::xml_document doc;
  pugi::xml_node decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  pugi::xml_node root = Element(doc, "e57Root", "Structure");
  root.append_attribute("xmlns") = "http://www.astm.org/COMMIT/E57/2010-e57-v1.0";
  StringElement(root, "formatName", "ASTM E57 3D Imaging Data File");
  StringElement(root, "guid", Guid(rng));
  IntegerElement(root, "versionMajor", 1);
  IntegerElement(root, "versionMinor", 0);
  StringElement(root, "e57LibraryVersion", "scanreg");
  StringElement(root, "coordinateMetadata", "");
  pugi::xml_node when = Element(root, "creationDateTime", "Structure");
  const double unix_now = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  FloatElement(when, "dateTimeValue", unix_now - kGpsEpochUnix + kGpsLeapSeconds);
  IntegerElement(when, "isAtomicClockReferenced", 0);
  pugi::xml_node data3d = Element(root, "data3D", "Vector");
  data3d.append_attribute("allowHeterogeneousChildren") = "0";
  for (std::size_t i = 0; i < scans.size(); ++i) ScanXml(data3d, scans[i], written[i], rng);
  Element(root, "images2D", "Vector").append_attribute("allowHeterogeneousChildren") = "0";
  std::ostringstream out;
  doc.save(out, "  ", pugi::format_default, pugi::encoding_utf8);
  return out.str();
}

}  // namespace

Status WriteE57(const std::filesystem::path& path, const std::vector<Scan>& scans, ProgressSink& progress,
                const CancelToken& cancel) {
  const std::string target = path.string();
  if (scans.empty()) return MakeError(ErrorCode::kInvalidArgument, target + ": no scan to write");
  std::size_t total = 0;
  for (const Scan& scan : scans) {
    if (Status s = scan.Validate(); !s) return s;
    if (scan.rows < 1 || scan.cols < 1) {
      return MakeError(ErrorCode::kInvalidArgument,
                       target + ": scan '" + scan.name + "' has an empty grid; E57 needs rows and columns");
    }
    total += scan.CountPoints();
    if (scan.HasTime() && scan.time_base != kAdjustedGpsTime && scan.time_base != kE57ScanSeconds)
      LogWarning(target + ": scan '" + scan.name + "' has times in " + scan.TimeBaseText() + ", which has no GPS date: they are written as E57 timeStamps without an acquisitionStart; "
                 "export las or ply to keep the base");
  }
  AtomicFile file(path);
  if (Status s = file.Open(); !s) return s;
  if (Status s = file.CloseForExternalWriter(); !s) return s;
  std::unique_ptr<std::FILE, e57::FileCloser> out(std::fopen(file.temp_path().c_str(), "wb"), &std::fclose);
  if (!out) return MakeError(ErrorCode::kIoError, target + ": cannot create the temporary file beside it");
  e57::PagedWriter writer(out.get(), target);
  std::vector<WrittenScan> written(scans.size());
  std::size_t done = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (Status s = WriteScanPoints(writer, scans[i], &written[i], &done, total, target, progress, cancel); !s) return s;
  }
  const std::string xml = DocumentXml(scans, written);
  if (Status s = writer.Align(8); !s) return s;
  const std::uint64_t xml_offset = writer.physical_offset();
  if (Status s = writer.Append(xml); !s) return s;
  if (Status s = writer.Finish(xml_offset, xml.size()); !s) return s;
  if (std::fclose(out.release()) != 0) return MakeError(ErrorCode::kIoError, target + ": write failed (disk full?)");
  if (Status s = file.Commit(); !s) return s;
  progress.Report(1.0, "writing " + path.filename().string());
  return Status::Ok();
}

}  // namespace scanreg::io
