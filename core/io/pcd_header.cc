#include "core/io/pcd_header.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <fstream>
#include <sstream>

namespace scanreg::io {
namespace {

constexpr std::uint64_t kMaxPoints = 2'000'000'000ULL;  // PCL indexes points with 32-bit integers
constexpr int kMaxHeaderLines = 64;

// A header line for an error message: printable characters only, at most 60.
std::string Shown(const std::string& line) {
  std::string out;
  for (char c : line.substr(0, 60)) out += (c >= 32 && c < 127) ? c : '?';
  return line.size() > 60 ? out + "..." : out;
}

bool ParseCount(const std::string& s, std::uint64_t* value) {
  if (s.empty() || s.size() > 19 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return false;
  *value = std::stoull(s);
  return true;
}

}  // namespace

std::uint64_t PcdHeader::RecordBytes() const {
  std::uint64_t bytes = 0;
  for (std::size_t i = 0; i < sizes.size(); ++i) bytes += std::uint64_t(sizes[i]) * std::uint64_t(counts[i]);
  return bytes;
}

bool PcdHeader::Has(const std::string& field) const {
  return std::find(fields.begin(), fields.end(), field) != fields.end();
}

Expected<PcdHeader> ReadPcdHeader(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return MakeError(ErrorCode::kNotFound, file + ": not a regular file; give the path of a .pcd file");
  }
  const std::uint64_t file_bytes = std::filesystem::file_size(path, ec);
  if (ec) return MakeError(ErrorCode::kIoError, file + ": cannot read its size (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) return MakeError(ErrorCode::kIoError, file + ": cannot be opened; check its permissions");
  auto bad = [&](int line, const std::string& text, const std::string& what) {
    return MakeError(ErrorCode::kParseError, file + ":" + std::to_string(line) + ": " + what +
                                                 (text.empty() ? "" : " ('" + Shown(text) + "')") +
                                                 "; is this a complete PCD file?");
  };
  PcdHeader h;
  bool have_width = false, have_height = false, have_points = false;
  int line_number = 0;
  std::string line;
  while (h.data.empty()) {
    if (++line_number > kMaxHeaderLines) return bad(line_number, "", "no DATA line in the first 64 header lines");
    if (!std::getline(in, line)) return bad(line_number, "", "the header ends before its DATA line");
    if (line.size() > 100000) return bad(line_number, "", "a header line longer than 100,000 characters");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string key;
    words >> key;
    std::vector<std::string> values;
    for (std::string w; words >> w;) values.push_back(w);
    if (key == "VERSION") continue;
    if (key == "VIEWPOINT") {  // PCL parses it again; a pose that is no pose is refused here, with its line
      const std::string what = "VIEWPOINT must be 7 finite numbers, tx ty tz qw qx qy qz, with a quaternion that is "
                               "not zero (the identity: VIEWPOINT 0 0 0 1 0 0 0)";
      if (values.size() != 7) return bad(line_number, line, what);
      double q2 = 0;
      for (std::size_t k = 0; k < values.size(); ++k) {
        char* end = nullptr;
        const double v = std::strtod(values[k].c_str(), &end);
        if (end == values[k].c_str() || *end != '\0' || !std::isfinite(v) ||
            std::abs(v) > std::numeric_limits<float>::max())
          return bad(line_number, line, what);
        if (k >= 3) q2 += v * v;
      }
      if (!(q2 > 1e-12)) return bad(line_number, line, what);
      continue;
    }
    if (key == "FIELDS" || key == "COLUMNS") {
      if (values.empty()) return bad(line_number, line, "FIELDS lists no field");
      h.fields = values;
    } else if (key == "SIZE") {
      h.sizes.clear();
      for (const std::string& v : values) {
        if (v != "1" && v != "2" && v != "4" && v != "8") return bad(line_number, line, "SIZE must be 1, 2, 4 or 8");
        h.sizes.push_back(std::stoi(v));
      }
    } else if (key == "TYPE") {
      h.types.clear();
      for (const std::string& v : values) {
        if (v != "I" && v != "U" && v != "F") return bad(line_number, line, "TYPE must be I, U or F");
        h.types.push_back(v[0]);
      }
    } else if (key == "COUNT") {
      h.counts.clear();
      for (const std::string& v : values) {
        std::uint64_t c = 0;
        if (!ParseCount(v, &c) || c < 1 || c > 100000) return bad(line_number, line, "COUNT must be 1 to 100000");
        h.counts.push_back(static_cast<int>(c));
      }
    } else if (key == "WIDTH" || key == "HEIGHT" || key == "POINTS") {
      std::uint64_t v = 0;
      if (values.size() != 1 || !ParseCount(values[0], &v) || v > kMaxPoints)
        return bad(line_number, line, key + " must be one whole number up to 2,000,000,000");
      (key == "WIDTH" ? h.width : key == "HEIGHT" ? h.height : h.points) = v;
      (key == "WIDTH" ? have_width : key == "HEIGHT" ? have_height : have_points) = true;
    } else if (key == "DATA") {
      if (values.size() != 1 || (values[0] != "ascii" && values[0] != "binary" && values[0] != "binary_compressed"))
        return bad(line_number, line, "DATA must be ascii, binary or binary_compressed");
      h.data = values[0];
    } else {
      return bad(line_number, line, "unknown header entry '" + Shown(key) + "'");
    }
  }
  const std::uint64_t offset = static_cast<std::uint64_t>(in.tellg());
  h.data_offset = offset;
  const std::string where = file + " (header)";
  auto inconsistent = [&](const std::string& what) {
    return MakeError(ErrorCode::kParseError, where + ": " + what + "; the file is damaged or was not written as PCD");
  };
  if (h.fields.empty()) return inconsistent("no FIELDS line");
  const std::size_t n = h.fields.size();
  if (h.counts.empty()) h.counts.assign(n, 1);
  if (h.sizes.size() != n || h.types.size() != n || h.counts.size() != n) {
    return inconsistent(std::to_string(n) + " FIELDS but " + std::to_string(h.sizes.size()) + " SIZE, " +
                        std::to_string(h.types.size()) + " TYPE and " + std::to_string(h.counts.size()) +
                        " COUNT entries");
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (h.types[i] == 'F' && h.sizes[i] != 4 && h.sizes[i] != 8)
      return inconsistent("field '" + Shown(h.fields[i]) + "' is TYPE F with SIZE " + std::to_string(h.sizes[i]) +
                          " (floats are 4 or 8 bytes)");
  }
  if (!h.Has("x") || !h.Has("y") || !h.Has("z")) return inconsistent("no x, y, z fields");
  if (h.RecordBytes() > (1u << 20)) return inconsistent("a point of more than 1 MiB");
  if (!have_width) return inconsistent("no WIDTH line");
  if (!have_height) h.height = 1;
  if (!have_points) h.points = h.width * h.height;
  if (h.width * h.height != h.points) {
    return inconsistent("POINTS " + std::to_string(h.points) + " is not WIDTH x HEIGHT (" + std::to_string(h.width) +
                        " x " + std::to_string(h.height) + ")");
  }
  if (h.points == 0) return inconsistent("no points (POINTS 0)");
  const std::uint64_t left = file_bytes > offset ? file_bytes - offset : 0;
  const std::uint64_t record = h.RecordBytes();
  if (h.data == "binary" && h.points * record > left) {
    return MakeError(ErrorCode::kParseError, file + ": truncated: the header declares " + std::to_string(h.points) +
                                                 " points of " + std::to_string(record) + " bytes (" +
                                                 std::to_string(h.points * record) + " bytes) but only " +
                                                 std::to_string(left) + " bytes follow it");
  }
  if (h.data == "binary_compressed") {
    std::uint32_t sizes[2] = {0, 0};
    if (left < 8 || !in.read(reinterpret_cast<char*>(sizes), 8)) {
      return MakeError(ErrorCode::kParseError, file + ": truncated: the compressed data's sizes are missing");
    }
    if (std::uint64_t(sizes[1]) != h.points * record) {
      return inconsistent("the compressed data unpacks to " + std::to_string(sizes[1]) + " bytes, not the " +
                          std::to_string(h.points * record) + " bytes the header declares");
    }
    if (std::uint64_t(sizes[0]) > left - 8) {
      return MakeError(ErrorCode::kParseError, file + ": truncated: " + std::to_string(sizes[0]) +
                                                   " compressed bytes declared, " + std::to_string(left - 8) +
                                                   " present");
    }
  }
  if (h.data == "ascii") {
    std::uint64_t values = 0;
    for (int c : h.counts) values += static_cast<std::uint64_t>(c);
    if (h.points * values * 2 > left + 1) {  // every value takes a digit and a separator at least
      return MakeError(ErrorCode::kParseError, file + ": truncated: the header declares " + std::to_string(h.points) +
                                                   " points but only " + std::to_string(left) +
                                                   " bytes of text follow it");
    }
  }
  return h;
}

}  // namespace scanreg::io
