// The header of a PLY file: format, elements and their properties, obj_info lines.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io {

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };
enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

int PlyTypeSize(PlyType type);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // value type (of the items, for a list)
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // for a list
};

struct PlyElement {
  std::string name;
  std::size_t count = 0;
  std::vector<PlyProperty> properties;
  int FindProperty(std::string_view name) const;  // index or -1
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  std::map<std::string, std::string> obj_info;  // first word -> rest of the line
  std::size_t body_offset = 0;                  // byte offset just after "end_header\n"
  long body_line = 0;                           // 1-based line number of the first body line
};

Expected<PlyHeader> ParsePlyHeader(std::string_view text, const std::filesystem::path& path);

}  // namespace scanreg::io
