#include "core/io/e57_xml.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <pugixml.hpp>

#include "core/io/e57_bitpack.h"

namespace scanreg::io::e57 {

namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\n' || s.front() == '\r' || s.front() == '\t'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\n' || s.back() == '\r' || s.back() == '\t'))
    s.remove_suffix(1);
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  return s;
}

template <typename T>
bool ParseText(std::string_view text, T* out) {
  text = Trim(text);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), *out);
  return ec == std::errc() && end == text.data() + text.size();
}

// Reads the XML of one scan; every error names the scan and the element.
class ScanParser {
 public:
  ScanParser(const std::string& source, int index) : where_(source + ": scan " + std::to_string(index + 1)) {}

  Expected<ScanDesc> Parse(const pugi::xml_node& node) {
    ScanDesc scan;
    scan.name = node.child("name").text().get();
    if (!scan.name.empty()) where_ += " ('" + scan.name + "')";
    scan.guid = node.child("guid").text().get();
    if (Status s = ParsePose(node.child("pose"), &scan); !s) return s.error();
    if (Status s = ParsePoints(node.child("points"), &scan); !s) return s.error();
    if (const pugi::xml_node b = node.child("indexBounds")) {
      IndexBounds bounds;
      const std::pair<const char*, std::int64_t*> items[] = {{"rowMinimum", &bounds.row_minimum},
                                                             {"rowMaximum", &bounds.row_maximum},
                                                             {"columnMinimum", &bounds.column_minimum},
                                                             {"columnMaximum", &bounds.column_maximum}};
      for (const auto& [name, out] : items) {
        double v = 0;
        if (Status s = Number(b.child(name), std::string("indexBounds/") + name, 0.0, &v); !s) return s.error();
        if (v != std::floor(v) || std::fabs(v) > 1e15)
          return Bad(std::string("indexBounds/") + name + " is not an integer");
        *out = static_cast<std::int64_t>(v);
      }
      scan.index_bounds = bounds;
    }
    if (const pugi::xml_node l = node.child("intensityLimits")) {
      double lo = 0, hi = 0;
      if (Status s = Number(l.child("intensityMinimum"), "intensityLimits/intensityMinimum", 0.0, &lo); !s)
        return s.error();
      if (Status s = Number(l.child("intensityMaximum"), "intensityLimits/intensityMaximum", 0.0, &hi); !s)
        return s.error();
      if (hi > lo) scan.intensity_limits = std::make_pair(lo, hi);
    }
    if (const pugi::xml_node l = node.child("colorLimits")) {
      double lo = 0, hi = 0;
      if (Status s = Number(l.child("colorRedMinimum"), "colorLimits/colorRedMinimum", 0.0, &lo); !s) return s.error();
      if (Status s = Number(l.child("colorRedMaximum"), "colorLimits/colorRedMaximum", 0.0, &hi); !s) return s.error();
      if (hi > lo) scan.colour_limits = std::make_pair(lo, hi);
    }
    if (const pugi::xml_node start = node.child("acquisitionStart").child("dateTimeValue")) {
      double t = 0;
      if (Status s = Number(start, "acquisitionStart/dateTimeValue", 0.0, &t); !s) return s.error();
      scan.acquisition_start = t;
    }
    return scan;
  }

 private:
  Error Bad(const std::string& what) const {
    return MakeError(ErrorCode::kParseError, where_ + ": " + what + "; the E57 XML is malformed");
  }

  // The value of an Integer, ScaledInteger or Float element; `fallback` when the element is absent.
  Status Number(const pugi::xml_node& node, const std::string& what, double fallback, double* out) const {
    if (!node) {
      *out = fallback;
      return Status::Ok();
    }
    const std::string type = node.attribute("type").value();
    const std::string_view text = node.text().get();
    if (type == "Float") {
      double v = 0;
      if (!Trim(text).empty() && !ParseText(text, &v))
        return Bad(what + " '" + std::string(text) + "' is not a number");
      if (!std::isfinite(v)) return Bad(what + " is NaN or infinite");
      *out = v;
      return Status::Ok();
    }
    if (type == "Integer" || type == "ScaledInteger") {
      std::int64_t raw = 0;
      if (!Trim(text).empty() && !ParseText(text, &raw))
        return Bad(what + " '" + std::string(text) + "' is not an integer");
      double scale = 1.0, offset = 0.0;
      if (type == "ScaledInteger") {
        if (Status s = DoubleAttr(node, "scale", what, 1.0, &scale); !s) return s;
        if (Status s = DoubleAttr(node, "offset", what, 0.0, &offset); !s) return s;
      }
      *out = double(raw) * scale + offset;
      return Status::Ok();
    }
    return Bad(what + " has type '" + type + "', expected Float, Integer or ScaledInteger");
  }

  Status DoubleAttr(const pugi::xml_node& node, const char* attr, const std::string& what, double fallback,
                    double* out) const {
    const pugi::xml_attribute a = node.attribute(attr);
    *out = fallback;
    if (!a) return Status::Ok();
    if (!ParseText(a.value(), out) || !std::isfinite(*out)) {
      return Bad(what + ": attribute " + attr + "=\"" + a.value() + "\" is not a finite number");
    }
    return Status::Ok();
  }

  Status IntAttr(const pugi::xml_node& node, const char* attr, const std::string& what, std::int64_t fallback,
                 std::int64_t* out) const {
    const pugi::xml_attribute a = node.attribute(attr);
    *out = fallback;
    if (a && !ParseText(a.value(), out)) {
      return Bad(what + ": attribute " + attr + "=\"" + a.value() + "\" is not a 64-bit integer");
    }
    return Status::Ok();
  }

  Status ParsePose(const pugi::xml_node& pose, ScanDesc* scan) const {
    if (!pose) return Status::Ok();
    double q[4], t[3];
    const char* qn[4] = {"w", "x", "y", "z"};
    const char* tn[3] = {"x", "y", "z"};
    const pugi::xml_node rotation = pose.child("rotation"), translation = pose.child("translation");
    for (int i = 0; i < 4; ++i) {
      if (Status s = Number(rotation.child(qn[i]), std::string("pose/rotation/") + qn[i], i == 0 ? 1.0 : 0.0, &q[i]);
          !s)
        return s;
    }
    for (int i = 0; i < 3; ++i) {
      if (Status s = Number(translation.child(tn[i]), std::string("pose/translation/") + tn[i], 0.0, &t[i]); !s)
        return s;
    }
    const Eigen::Quaterniond quaternion(q[0], q[1], q[2], q[3]);
    if (std::fabs(quaternion.norm() - 1.0) > 1e-3) {
      return Bad("pose/rotation is not a unit quaternion (norm " + std::to_string(quaternion.norm()) + ")");
    }
    scan->world_from_scan.linear() = quaternion.normalized().toRotationMatrix();
    scan->world_from_scan.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
    scan->has_pose = true;
    return Status::Ok();
  }

  Status ParsePoints(const pugi::xml_node& points, ScanDesc* scan) const {
    if (!points) return Bad("no 'points' element");
    if (std::string(points.attribute("type").value()) != "CompressedVector") {
      return Bad("'points' is not a CompressedVector");
    }
    std::int64_t offset = 0, count = 0;
    if (Status s = IntAttr(points, "fileOffset", "points", -1, &offset); !s) return s;
    if (Status s = IntAttr(points, "recordCount", "points", -1, &count); !s) return s;
    if (offset < 0 || count < 0) return Bad("'points' lacks a valid fileOffset or recordCount attribute");
    scan->points_offset = static_cast<std::uint64_t>(offset);
    scan->record_count = static_cast<std::uint64_t>(count);
    const pugi::xml_node prototype = points.child("prototype");
    if (!prototype) return Bad("'points' has no prototype");
    for (const pugi::xml_node& child : prototype.children()) {
      if (child.type() != pugi::node_element) continue;
      Field field;
      if (Status s = ParseField(child, &field); !s) return s;
      scan->fields.push_back(std::move(field));
    }
    if (scan->fields.empty()) return Bad("the points prototype has no field");
    const bool cartesian = scan->FieldIndex("cartesianX") >= 0 && scan->FieldIndex("cartesianY") >= 0 &&
                           scan->FieldIndex("cartesianZ") >= 0;
    const bool spherical = scan->FieldIndex("sphericalRange") >= 0 && scan->FieldIndex("sphericalAzimuth") >= 0 &&
                           scan->FieldIndex("sphericalElevation") >= 0;
    if (!cartesian && !spherical) {
      return Bad("the points have neither cartesianX/Y/Z nor sphericalRange/Azimuth/Elevation");
    }
    return Status::Ok();
  }

  Status ParseField(const pugi::xml_node& node, Field* field) const {
    field->name = node.name();
    const std::string what = "points/prototype/" + field->name;
    const std::string type = node.attribute("type").value();
    if (type == "Float") {
      field->type = FieldType::kFloat;
      const std::string precision = node.attribute("precision").value();
      if (!precision.empty() && precision != "single" && precision != "double") {
        return Bad(what + ": precision '" + precision + "' is neither single nor double");
      }
      field->single_precision = precision == "single";
      field->bits = field->single_precision ? 32 : 64;
      for (auto [attr, out] :
           {std::make_pair("minimum", &field->float_minimum), std::make_pair("maximum", &field->float_maximum)}) {
        double v = 0;
        if (node.attribute(attr)) {
          if (Status s = DoubleAttr(node, attr, what, 0.0, &v); !s) return s;
          *out = v;
        }
      }
      return Status::Ok();
    }
    if (type != "Integer" && type != "ScaledInteger") {
      return MakeError(ErrorCode::kUnsupported, where_ + ": " + what + " has type '" + type +
                                                    "'; only Float, Integer and ScaledInteger point fields are read");
    }
    field->type = type == "Integer" ? FieldType::kInteger : FieldType::kScaledInteger;
    if (Status s = IntAttr(node, "minimum", what, std::numeric_limits<std::int64_t>::min(), &field->minimum); !s)
      return s;
    if (Status s = IntAttr(node, "maximum", what, std::numeric_limits<std::int64_t>::max(), &field->maximum); !s)
      return s;
    if (field->minimum > field->maximum) {
      return Bad(what + ": minimum " + std::to_string(field->minimum) + " is larger than maximum " +
                 std::to_string(field->maximum));
    }
    if (field->type == FieldType::kScaledInteger) {
      if (Status s = DoubleAttr(node, "scale", what, 1.0, &field->scale); !s) return s;
      if (Status s = DoubleAttr(node, "offset", what, 0.0, &field->offset); !s) return s;
      if (field->scale == 0.0) return Bad(what + ": scale is 0");
    }
    field->bits = BitWidth(field->minimum, field->maximum);
    return Status::Ok();
  }

  std::string where_;
};

}  // namespace

std::optional<std::pair<double, double>> Field::ValueLimits() const {
  if (type == FieldType::kFloat) {
    if (float_minimum && float_maximum) return std::make_pair(*float_minimum, *float_maximum);
    return std::nullopt;
  }
  const double a = double(minimum) * scale + offset, b = double(maximum) * scale + offset;
  return std::make_pair(std::min(a, b), std::max(a, b));
}

int ScanDesc::FieldIndex(std::string_view field_name) const {
  for (std::size_t i = 0; i < fields.size(); ++i)
    if (fields[i].name == field_name) return static_cast<int>(i);
  return -1;
}

Expected<std::vector<ScanDesc>> ParseE57Xml(std::string_view xml, const std::string& source) {
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(xml.data(), xml.size());
  if (!parsed) {
    return MakeError(ErrorCode::kParseError, source + ": the XML section is not valid XML (" + parsed.description() +
                                                 " at byte " + std::to_string(parsed.offset) +
                                                 "); the file is damaged");
  }
  const pugi::xml_node root = doc.child("e57Root");
  if (!root) {
    return MakeError(ErrorCode::kParseError, source + ": the XML has no e57Root element; this is not an E57 file");
  }
  const pugi::xml_node data3d = root.child("data3D");
  if (!data3d) {
    return MakeError(ErrorCode::kParseError, source + ": the XML has no data3D element (the list of 3D scans)");
  }
  std::vector<ScanDesc> scans;
  for (const pugi::xml_node& child : data3d.children()) {
    if (child.type() != pugi::node_element) continue;
    Expected<ScanDesc> scan = ScanParser(source, static_cast<int>(scans.size())).Parse(child);
    if (!scan) return scan.error();
    scans.push_back(std::move(*scan));
  }
  return scans;
}

}  // namespace scanreg::io::e57
