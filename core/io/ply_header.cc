#include "core/io/ply_header.h"

#include <charconv>

#include "core/io/text_parse.h"

namespace scanreg::io {

int PlyTypeSize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 4;
}

int PlyElement::FindProperty(std::string_view prop) const {
  for (std::size_t i = 0; i < properties.size(); ++i)
    if (properties[i].name == prop) return static_cast<int>(i);
  return -1;
}

namespace {

bool ParseType(std::string_view s, PlyType* type) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [name, t] : kNames) {
    if (s == name) {
      *type = t;
      return true;
    }
  }
  return false;
}

}  // namespace

Expected<PlyHeader> ParsePlyHeader(std::string_view text, const std::filesystem::path& path) {
  auto err = [&](long line, const std::string& what) {
    return MakeError(ErrorCode::kParseError, AtLine(path, line) + what);
  };
  LineReader lines(text);
  std::string_view line;
  if (!lines.Next(&line) || line != "ply") {
    return err(1, text.empty() ? "the file is empty; export the scan again"
                               : "not a PLY file (the first line must be \"ply\")");
  }
  PlyHeader header;
  bool have_format = false;
  while (true) {
    if (!lines.Next(&line)) return err(lines.line_number() + 1, "the file ends before \"end_header\"");
    std::string_view rest = line;
    const std::string_view key = NextToken(&rest);
    const long n = lines.line_number();
    if (key.empty() || key == "comment") continue;
    if (key == "end_header") break;
    if (key == "format") {
      const std::string_view f = NextToken(&rest);
      if (f == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (f == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (f == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        return err(
            n, "unknown PLY format " + QuoteToken(f) + "; expected ascii, binary_little_endian or binary_big_endian");
      }
      have_format = true;
    } else if (key == "obj_info") {
      const std::string_view name = NextToken(&rest);
      while (!rest.empty() && (rest.front() == ' ' || rest.front() == '\t')) rest.remove_prefix(1);
      header.obj_info[std::string(name)] = std::string(rest);
    } else if (key == "element") {
      PlyElement element;
      element.name = std::string(NextToken(&rest));
      const std::string_view count = NextToken(&rest);
      auto [ptr, ec] = std::from_chars(count.data(), count.data() + count.size(), element.count);
      if (element.name.empty() || ec != std::errc() || ptr != count.data() + count.size()) {
        return err(n, "malformed element line; expected \"element <name> <count>\"");
      }
      header.elements.push_back(std::move(element));
    } else if (key == "property") {
      if (header.elements.empty()) return err(n, "property before any element");
      PlyProperty prop;
      std::string_view type = NextToken(&rest);
      if (type == "list") {
        prop.is_list = true;
        if (!ParseType(NextToken(&rest), &prop.count_type)) return err(n, "unknown list count type");
        type = NextToken(&rest);
      }
      if (!ParseType(type, &prop.type)) return err(n, "unknown property type " + QuoteToken(type));
      prop.name = std::string(NextToken(&rest));
      if (prop.name.empty()) return err(n, "property without a name");
      header.elements.back().properties.push_back(std::move(prop));
    } else {
      return err(n, "unknown header keyword " + QuoteToken(key) + "; is the PLY header damaged?");
    }
  }
  if (!have_format) return err(lines.line_number(), "the header has no \"format\" line");
  header.body_offset = lines.offset();
  header.body_line = lines.line_number() + 1;
  // The declared counts must fit the bytes that follow, before anyone allocates for them: a binary
  // record takes at least its fixed-size properties (a list at least its count), an ASCII one at
  // least a digit and a separator per property.
  const double left = static_cast<double>(text.size() - header.body_offset);
  double needed = 0;
  for (const PlyElement& e : header.elements) {
    double record = 0;
    for (const PlyProperty& p : e.properties)
      record += header.format == PlyFormat::kAscii ? 2.0 : PlyTypeSize(p.is_list ? p.count_type : p.type);
    needed += record * static_cast<double>(e.count);
    if (needed > left + 1) {
      return MakeError(ErrorCode::kParseError,
                       path.string() + ": the header declares " + std::to_string(e.count) + " '" + e.name +
                           "' records, which need at least " + std::to_string(static_cast<long long>(needed)) +
                           " bytes, but " + std::to_string(static_cast<long long>(left)) +
                           " follow the header; the file is truncated or its header is damaged");
    }
  }
  return header;
}

}  // namespace scanreg::io
