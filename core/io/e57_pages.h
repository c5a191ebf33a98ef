// E57 (ASTM E2807) paged file access: 1024-byte physical pages, each holding 1020 logical bytes and
// a CRC-32C (Castagnoli) checksum of them, stored big-endian in the page's last 4 bytes. Offsets
// in the file header and the XML are physical; the data they point at is read logically (the
// checksums skipped). The 48-byte file header opens page 0.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "core/common/expected.h"

namespace scanreg::io::e57 {

constexpr std::uint64_t kPageSize = 1024;
constexpr std::uint64_t kPageData = 1020;
constexpr std::size_t kHeaderSize = 48;

std::uint32_t Crc32c(const void* data, std::size_t size);

inline std::uint64_t LogicalFromPhysical(std::uint64_t physical) {
  return physical / kPageSize * kPageData + physical % kPageSize;
}
inline std::uint64_t PhysicalFromLogical(std::uint64_t logical) {
  return logical / kPageData * kPageSize + logical % kPageData;
}

// Little-endian integers, as every binary field of E57 is stored.
template <typename T>
T LoadLe(const char* p) {
  T v = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) v |= T(static_cast<unsigned char>(p[i])) << (8 * i);
  return v;
}

template <typename T>
void StoreLe(char* p, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) p[i] = static_cast<char>((v >> (8 * i)) & 0xFF);
}

struct FileHeader {
  std::uint32_t version_major = 1;
  std::uint32_t version_minor = 0;
  std::uint64_t file_physical_length = 0;
  std::uint64_t xml_physical_offset = 0;
  std::uint64_t xml_logical_length = 0;
  std::uint64_t page_size = kPageSize;
};

using FileCloser = int (*)(std::FILE*);

// Reads logical bytes of an E57 file, checking the checksum of every page it touches.
class PagedReader {
 public:
  // Opens the file and checks its header: signature, version 1, page size, length.
  static Expected<PagedReader> Open(const std::filesystem::path& path);

  const FileHeader& header() const { return header_; }
  // Logical bytes in the file (the pages without their checksums).
  std::uint64_t logical_length() const { return header_.file_physical_length / kPageSize * kPageData; }
  // n logical bytes starting at a physical offset; `what` names the data in error messages.
  Status Read(std::uint64_t physical_offset, std::uint64_t n, const std::string& what, std::string* out);
  // The XML section, as text.
  Status ReadXml(std::string* out);
  const std::string& source() const { return source_; }

 private:
  PagedReader(std::unique_ptr<std::FILE, FileCloser> file, std::string source, FileHeader header)
      : file_(std::move(file)), source_(std::move(source)), header_(header) {}

  std::unique_ptr<std::FILE, FileCloser> file_;
  std::string source_;
  FileHeader header_;
};

// Writes logical bytes as checksummed pages to a file opened by the caller. Starts with room for
// the file header, which Finish() fills in.
class PagedWriter {
 public:
  PagedWriter(std::FILE* file, std::string target);

  Status Append(std::string_view bytes);
  // Zero bytes up to the next multiple of `alignment` logical bytes.
  Status Align(std::uint64_t alignment);
  std::uint64_t logical_size() const { return logical_size_; }
  std::uint64_t physical_offset() const { return PhysicalFromLogical(logical_size_); }
  // Pads the last page, then rewrites page 0 with the header (the XML section's place given).
  Status Finish(std::uint64_t xml_physical_offset, std::uint64_t xml_logical_length);

 private:
  Status EmitPage();

  std::FILE* file_;
  std::string target_;
  std::string page_;   // the logical bytes of the page being filled
  std::string page0_;  // page 0's logical bytes, patched by Finish()
  std::uint64_t logical_size_ = 0;
  std::uint64_t pages_written_ = 0;
};

}  // namespace scanreg::io::e57
