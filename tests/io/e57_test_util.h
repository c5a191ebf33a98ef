// Helpers for the E57 tests: a file's logical bytes and back, and edits of its XML behind valid
// checksums.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <string>

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

}  // namespace scanreg::test
