#include "core/io/e57_pages.h"

#include <array>
#include <cstring>

#if defined(__x86_64__)
#include <nmmintrin.h>
#endif

namespace scanreg::io::e57 {

namespace {

constexpr char kSignature[8] = {'A', 'S', 'T', 'M', '-', 'E', '5', '7'};

std::array<std::uint32_t, 256> MakeCrcTable() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;  // reflected Castagnoli
    table[i] = c;
  }
  return table;
}

std::uint32_t Crc32cTable(const unsigned char* p, std::size_t n, std::uint32_t crc) {
  static const std::array<std::uint32_t, 256> table = MakeCrcTable();
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ p[i]) & 0xFF] ^ (crc >> 8);
  return crc;
}

#if defined(__x86_64__)
__attribute__((target("sse4.2"))) std::uint32_t Crc32cSse42(const unsigned char* p, std::size_t n, std::uint32_t crc) {
  std::uint64_t c = crc;
  for (; n >= 8; n -= 8, p += 8) {
    std::uint64_t word;
    std::memcpy(&word, p, 8);
    c = _mm_crc32_u64(c, word);
  }
  std::uint32_t c32 = static_cast<std::uint32_t>(c);
  for (; n > 0; --n, ++p) c32 = _mm_crc32_u8(c32, *p);
  return c32;
}
#endif

// Checks the checksum of one physical page; false when it does not match.
bool PageChecksumOk(const char* page) {
  const std::uint32_t crc = Crc32c(page, kPageData);
  const auto* b = reinterpret_cast<const unsigned char*>(page + kPageData);
  const std::uint32_t stored =
      (std::uint32_t(b[0]) << 24) | (std::uint32_t(b[1]) << 16) | (std::uint32_t(b[2]) << 8) | std::uint32_t(b[3]);
  return crc == stored;
}

void SetPageChecksum(char* page) {
  const std::uint32_t crc = Crc32c(page, kPageData);
  for (int i = 0; i < 4; ++i) page[kPageData + i] = static_cast<char>((crc >> (24 - 8 * i)) & 0xFF);
}

Error Damaged(const std::string& source, const std::string& what) {
  return MakeError(ErrorCode::kParseError, source + ": " + what);
}

}  // namespace

std::uint32_t Crc32c(const void* data, std::size_t size) {
  const auto* p = static_cast<const unsigned char*>(data);
#if defined(__x86_64__)
  static const bool has_sse42 = __builtin_cpu_supports("sse4.2");
  if (has_sse42) return ~Crc32cSse42(p, size, ~0u);
#endif
  return ~Crc32cTable(p, size, ~0u);
}

Expected<PagedReader> PagedReader::Open(const std::filesystem::path& path) {
  const std::string source = path.string();
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(source.c_str(), "rb"), &std::fclose);
  if (!file) {
    return MakeError(ErrorCode::kIoError,
                     source + ": cannot open the file for reading; check the path and permissions");
  }
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return MakeError(ErrorCode::kIoError, source + ": cannot get the file size (" + ec.message() + ")");
  char page[kPageSize];
  if (size < kPageSize || std::fread(page, 1, kPageSize, file.get()) != kPageSize) {
    return Damaged(source, "only " + std::to_string(size) +
                               " bytes; an E57 file is at least one 1024-byte page. The file is truncated or not E57");
  }
  if (std::memcmp(page, kSignature, sizeof(kSignature)) != 0) {
    return Damaged(source, "does not start with \"ASTM-E57\"; this is not an E57 file");
  }
  if (!PageChecksumOk(page)) {
    return Damaged(source, "page 0 (the file header) fails its CRC-32C checksum; the file is damaged, copy it again");
  }
  FileHeader h;
  h.version_major = LoadLe<std::uint32_t>(page + 8);
  h.version_minor = LoadLe<std::uint32_t>(page + 12);
  h.file_physical_length = LoadLe<std::uint64_t>(page + 16);
  h.xml_physical_offset = LoadLe<std::uint64_t>(page + 24);
  h.xml_logical_length = LoadLe<std::uint64_t>(page + 32);
  h.page_size = LoadLe<std::uint64_t>(page + 40);
  if (h.version_major != 1) {
    return MakeError(ErrorCode::kUnsupported, source + ": E57 version " + std::to_string(h.version_major) + "." +
                                                  std::to_string(h.version_minor) + " is not supported (only 1.x)");
  }
  if (h.page_size != kPageSize) {
    return MakeError(ErrorCode::kUnsupported,
                     source + ": page size " + std::to_string(h.page_size) + " is not supported (only 1024)");
  }
  if (h.file_physical_length > size || size % kPageSize != 0) {
    return Damaged(source, "the header says " + std::to_string(h.file_physical_length) + " bytes but the file has " +
                               std::to_string(size) + "; the file is truncated, copy or export it again");
  }
  if (h.file_physical_length % kPageSize != 0 || h.xml_physical_offset % kPageSize >= kPageData ||
      h.xml_physical_offset >= h.file_physical_length ||
      LogicalFromPhysical(h.xml_physical_offset) + h.xml_logical_length >
          h.file_physical_length / kPageSize * kPageData) {
    return Damaged(source, "the file header's lengths and XML offset are inconsistent; the file is damaged");
  }
  return PagedReader(std::move(file), source, h);
}

Status PagedReader::Read(std::uint64_t physical_offset, std::uint64_t n, const std::string& what, std::string* out) {
  const std::uint64_t logical_end_of_file = logical_length();
  const std::uint64_t begin = LogicalFromPhysical(physical_offset);
  if (physical_offset % kPageSize >= kPageData || begin > logical_end_of_file || n > logical_end_of_file - begin) {
    return Damaged(source_, what + " (physical offset " + std::to_string(physical_offset) + ", " + std::to_string(n) +
                                " bytes) lies outside the file; the file is truncated or damaged");
  }
  out->clear();
  out->reserve(n);
  constexpr std::uint64_t kPagesPerRead = 256;
  std::string block;
  std::uint64_t logical = begin;
  while (out->size() < n) {
    const std::uint64_t first_page = logical / kPageData;
    const std::uint64_t last_page = (begin + n - 1) / kPageData;
    const std::uint64_t pages = std::min(kPagesPerRead, last_page - first_page + 1);
    block.resize(pages * kPageSize);
    if (std::fseek(file_.get(), static_cast<long>(first_page * kPageSize), SEEK_SET) != 0 ||
        std::fread(block.data(), 1, block.size(), file_.get()) != block.size()) {
      return MakeError(ErrorCode::kIoError, source_ + ": cannot read " + what + " (page " + std::to_string(first_page) +
                                                "); the file is truncated or unreadable");
    }
    for (std::uint64_t k = 0; k < pages && out->size() < n; ++k) {
      const char* page = block.data() + k * kPageSize;
      if (!PageChecksumOk(page)) {
        return Damaged(source_, "page " + std::to_string(first_page + k) + " (physical offset " +
                                    std::to_string((first_page + k) * kPageSize) + ", in " + what +
                                    ") fails its CRC-32C checksum; the file is damaged, copy or export it again");
      }
      const std::uint64_t from = logical % kPageData;
      const std::uint64_t take = std::min(kPageData - from, n - out->size());
      out->append(page + from, take);
      logical += take;
    }
  }
  return Status::Ok();
}

Status PagedReader::ReadXml(std::string* out) {
  return Read(header_.xml_physical_offset, header_.xml_logical_length, "the XML section", out);
}

PagedWriter::PagedWriter(std::FILE* file, std::string target) : file_(file), target_(std::move(target)) {
  page_.reserve(kPageData);
  page_.assign(kHeaderSize, '\0');  // the header, filled in by Finish()
  logical_size_ = kHeaderSize;
}

Status PagedWriter::EmitPage() {
  char physical[kPageSize] = {};
  std::memcpy(physical, page_.data(), page_.size());
  if (pages_written_ == 0) page0_.assign(physical, kPageData);
  SetPageChecksum(physical);
  if (std::fwrite(physical, 1, kPageSize, file_) != kPageSize) {
    return MakeError(ErrorCode::kIoError, target_ + ": write failed (disk full?)");
  }
  ++pages_written_;
  page_.clear();
  return Status::Ok();
}

Status PagedWriter::Append(std::string_view bytes) {
  while (!bytes.empty()) {
    const std::size_t take = std::min<std::size_t>(kPageData - page_.size(), bytes.size());
    page_.append(bytes.data(), take);
    bytes.remove_prefix(take);
    logical_size_ += take;
    if (page_.size() == kPageData) {
      if (Status s = EmitPage(); !s) return s;
    }
  }
  return Status::Ok();
}

Status PagedWriter::Align(std::uint64_t alignment) {
  const std::uint64_t pad = (alignment - logical_size_ % alignment) % alignment;
  return Append(std::string(pad, '\0'));
}

Status PagedWriter::Finish(std::uint64_t xml_physical_offset, std::uint64_t xml_logical_length) {
  if (!page_.empty() || pages_written_ == 0) {
    if (Status s = EmitPage(); !s) return s;
  }
  char* h = page0_.data();
  std::memcpy(h, kSignature, sizeof(kSignature));
  StoreLe<std::uint32_t>(h + 8, 1);
  StoreLe<std::uint32_t>(h + 12, 0);
  StoreLe<std::uint64_t>(h + 16, pages_written_ * kPageSize);
  StoreLe<std::uint64_t>(h + 24, xml_physical_offset);
  StoreLe<std::uint64_t>(h + 32, xml_logical_length);
  StoreLe<std::uint64_t>(h + 40, kPageSize);
  char physical[kPageSize] = {};
  std::memcpy(physical, page0_.data(), kPageData);
  SetPageChecksum(physical);
  if (std::fflush(file_) != 0 || std::fseek(file_, 0, SEEK_SET) != 0 ||
      std::fwrite(physical, 1, kPageSize, file_) != kPageSize || std::fflush(file_) != 0) {
    return MakeError(ErrorCode::kIoError, target_ + ": write failed (disk full?)");
  }
  return Status::Ok();
}

}  // namespace scanreg::io::e57
