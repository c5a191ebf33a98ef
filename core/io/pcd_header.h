// The text header of a PCD file, checked against itself and the file's size before PCL reads a
// byte of data: PCL trusts the header (a declared size larger than the file allocates gigabytes or
// crashes; inconsistent field lists are read as garbage or zero points).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"

namespace scanreg::io {

struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<int> sizes;    // bytes per value: 1, 2, 4 or 8
  std::vector<char> types;   // 'I', 'U' or 'F'
  std::vector<int> counts;   // values per field
  std::uint64_t width = 0, height = 0, points = 0;
  std::string data;          // "ascii", "binary" or "binary_compressed"
  std::uint64_t data_offset = 0;  // bytes before the data
  std::uint64_t RecordBytes() const;
  bool Has(const std::string& field) const;
};

// Reads and checks the header of `path` (a regular file). Errors name the file and the header line
// and say what is wrong: unknown or missing entries, SIZE/TYPE/COUNT not matching FIELDS, POINTS not
// WIDTH x HEIGHT, no x/y/z, or more data declared than the file holds.
Expected<PcdHeader> ReadPcdHeader(const std::filesystem::path& path);

}  // namespace scanreg::io
