// Helpers for the E57 tests: a file's logical bytes and back, and edits of its XML behind valid
// checksums.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <pugixml.hpp>
#include <string>
#include <vector>

#include "core/io/e57_pages.h"

namespace scanreg::test {

// The logical bytes of an E57 file (checksums dropped) and back (checksums recomputed), so tests
// can damage the content behind valid checksums.
inline std::string LogicalBytes(const std::string& file) {
  std::string out;
  for (std::size_t p = 0; p + io::e57::kPageSize <= file.size(); p += io::e57::kPageSize)
    out.append(file, p, io::e57::kPageData);
  return out;
}

inline std::string PagedBytes(const std::string& logical) {
  std::string out;
  for (std::size_t p = 0; p < logical.size(); p += io::e57::kPageData) {
    std::string page = logical.substr(p, io::e57::kPageData);
    page.resize(io::e57::kPageData, '\0');
    const std::uint32_t crc = io::e57::Crc32c(page.data(), page.size());
    for (int i = 0; i < 4; ++i) page.push_back(static_cast<char>((crc >> (24 - 8 * i)) & 0xFF));
    out += page;
  }
  return out;
}

// The file with its XML section (the last thing our writer puts in a file) replaced by
// edit(xml), lengths and checksums updated.
inline std::string WithXml(const std::string& file, const std::function<std::string(std::string)>& edit) {
  std::string logical = LogicalBytes(file);
  std::uint64_t xml_offset = 0, xml_length = 0;
  std::memcpy(&xml_offset, &logical[24], 8);
  std::memcpy(&xml_length, &logical[32], 8);
  const std::uint64_t start = io::e57::LogicalFromPhysical(xml_offset);
  const std::string xml = edit(logical.substr(start, xml_length));
  logical.resize(start);
  logical += xml;
  xml_length = xml.size();
  const std::uint64_t physical_length =
      (logical.size() + io::e57::kPageData - 1) / io::e57::kPageData * io::e57::kPageSize;
  std::memcpy(&logical[32], &xml_length, 8);
  std::memcpy(&logical[16], &physical_length, 8);
  return PagedBytes(logical);
}

// Replaces every `from` by `to` in the file's XML.
inline std::string EditXml(const std::string& file, const std::string& from, const std::string& to) {
  return WithXml(file, [&](std::string xml) {
    EXPECT_NE(xml.find(from), std::string::npos) << from;
    for (std::size_t at = xml.find(from); at != std::string::npos; at = xml.find(from, at + to.size()))
      xml.replace(at, from.size(), to);
    return xml;
  });
}

inline bool Has(const std::string& message, const std::string& part) { return message.find(part) != std::string::npos; }

// One scan of an E57 file as the standard lays it out (ASTM E2807), decoded here and not by
// scanreg's reader: the pages (1020 data bytes and a checksum each), the XML section (its offset
// and length at bytes 24 and 32 of the header), the CompressedVector section (the data's offset at
// byte 16 of its header) and its data packets (type, flags, length - 1, bytestream count, each
// bytestream's length, the bytestreams). A field's bytestream runs on across packets: Float values
// as 4 or 8 little-endian bytes, Integer and ScaledInteger values as value - minimum in the fewest
// bits that hold maximum - minimum, packed from the least significant bit.
struct E57BySpecification {
  std::vector<std::string> fields;          // the prototype's fields, in order
  std::vector<std::vector<double>> values;  // values[f][record]; ScaledInteger scaled
  std::optional<double> acquisition_start;  // acquisitionStart/dateTimeValue
  Eigen::Isometry3d world_from_scan = Eigen::Isometry3d::Identity();  // pose: rotation (w x y z), translation
  std::size_t records = 0;
  // Record r's cartesianX/Y/Z in the world (through the pose).
  Eigen::Vector3d World(std::size_t r) const {
    return world_from_scan * Eigen::Vector3d(Field("cartesianX")[r], Field("cartesianY")[r], Field("cartesianZ")[r]);
  }
  // The values of the named field, or an empty vector.
  const std::vector<double>& Field(const std::string& name) const {
    static const std::vector<double> none;
    for (std::size_t i = 0; i < fields.size(); ++i)
      if (fields[i] == name) return values[i];
    return none;
  }
};

inline E57BySpecification DecodeE57BySpecification(const std::string& file, int scan_index = 0) {
  E57BySpecification out;
  const std::string logical = LogicalBytes(file);
  const auto to_logical = [](std::uint64_t physical) { return physical / 1024 * 1020 + physical % 1024; };
  const auto u64 = [&](std::uint64_t at) {
    std::uint64_t v = 0;
    if (at + 8 <= logical.size()) std::memcpy(&v, &logical[at], 8);
    return v;
  };
  pugi::xml_document doc;
  const std::uint64_t xml_at = to_logical(u64(24)), xml_length = u64(32);
  if (xml_at + xml_length > logical.size() || !doc.load_string(logical.substr(xml_at, xml_length).c_str())) {
    ADD_FAILURE() << "no readable XML section";
    return out;
  }
  pugi::xml_node scan = doc.child("e57Root").child("data3D").first_child();
  for (int i = 0; i < scan_index && scan; ++i) scan = scan.next_sibling();
  if (const pugi::xml_node t = scan.child("acquisitionStart").child("dateTimeValue"))
    out.acquisition_start = std::stod(t.text().get());
  if (const pugi::xml_node pose = scan.child("pose")) {
    const pugi::xml_node q = pose.child("rotation"), t = pose.child("translation");
    out.world_from_scan.linear() = Eigen::Quaterniond(q.child("w").text().as_double(1), q.child("x").text().as_double(),
                                                      q.child("y").text().as_double(), q.child("z").text().as_double())
                                       .normalized()
                                       .toRotationMatrix();
    out.world_from_scan.translation() =
        Eigen::Vector3d(t.child("x").text().as_double(), t.child("y").text().as_double(), t.child("z").text().as_double());
  }
  const pugi::xml_node points = scan.child("points");
  struct Kind {
    bool is_float = true;
    int bytes = 8, bits = 0;
    double minimum = 0, scale = 1, offset = 0;
  };
  std::vector<Kind> kinds;
  for (pugi::xml_node f = points.child("prototype").first_child(); f; f = f.next_sibling()) {
    Kind k;
    const std::string type = f.attribute("type").value();
    k.is_float = type == "Float";
    if (k.is_float) {
      k.bytes = std::string(f.attribute("precision").value()) == "single" ? 4 : 8;
    } else {
      const double lo = f.attribute("minimum").as_llong(), hi = f.attribute("maximum").as_llong();
      k.minimum = lo;
      while (std::ldexp(1.0, k.bits) < hi - lo + 1) ++k.bits;
      if (type == "ScaledInteger") k.scale = f.attribute("scale").as_double(1.0), k.offset = f.attribute("offset").as_double();
    }
    out.fields.push_back(f.name());
    kinds.push_back(k);
  }
  out.records = std::stoull(points.attribute("recordCount").value());
  const std::uint64_t section = to_logical(std::stoull(points.attribute("fileOffset").value()));
  const std::uint64_t section_end = section + u64(section + 8);
  std::vector<std::string> streams(kinds.size());
  for (std::uint64_t at = to_logical(u64(section + 16)); at + 6 <= section_end && at + 6 <= logical.size();) {
    std::uint16_t length = 0, count = 0;
    std::memcpy(&length, &logical[at + 2], 2);
    std::memcpy(&count, &logical[at + 4], 2);
    if (logical[at] == 1) {  // a data packet; index (0) and empty (2) packets hold no values
      EXPECT_EQ(count, kinds.size());
      std::uint64_t pos = at + 6 + 2 * std::uint64_t(count);
      for (std::size_t s = 0; s < count && s < streams.size(); ++s) {
        std::uint16_t n = 0;
        std::memcpy(&n, &logical[at + 6 + 2 * s], 2);
        streams[s].append(logical, pos, n);
        pos += n;
      }
    }
    at += std::uint64_t(length) + 1;
  }
  for (std::size_t f = 0; f < kinds.size(); ++f) {
    const Kind& k = kinds[f];
    std::vector<double> v;
    for (std::size_t r = 0; r < out.records; ++r) {
      if (k.is_float) {
        if ((r + 1) * k.bytes > streams[f].size()) break;
        if (k.bytes == 4) {
          float x;
          std::memcpy(&x, &streams[f][r * 4], 4);
          v.push_back(x);
        } else {
          double x;
          std::memcpy(&x, &streams[f][r * 8], 8);
          v.push_back(x);
        }
        continue;
      }
      std::uint64_t raw = 0;
      for (int b = 0; b < k.bits; ++b) {
        const std::uint64_t bit = std::uint64_t(r) * k.bits + b;
        if (bit / 8 >= streams[f].size()) break;
        raw |= std::uint64_t((static_cast<unsigned char>(streams[f][bit / 8]) >> (bit % 8)) & 1u) << b;
      }
      v.push_back((double(raw) + k.minimum) * k.scale + k.offset);
    }
    out.values.push_back(std::move(v));
  }
  return out;
}

}  // namespace scanreg::test
