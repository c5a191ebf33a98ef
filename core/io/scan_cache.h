// A binary copy of each scan file beside the project (issue 13, item 2), so that reopening a
// project of many scans reads arrays instead of re-parsing text (PTX parses at ~6 M points/s).
//
// One entry per source file, "<cache_dir>/scans_<8 hex of the path>_<16 hex key>.scan", the key a
// hash of the source file's bytes (a changed file is a new key: never a stale entry); writing a
// file's new entry removes its superseded ones, so the cache holds one entry per file. Native
// little-endian:
//   char[8] magic "SRGSCAN\0" | u32 version (2) | u32 scans n | u64 key |
//   u64 offsets[n + 1] (each scan's record from the entry's start; the last: the entry's size) |
//   u64 checksum of the header before it |
//   per scan, its record: u32 name bytes, name | i32 rows | i32 cols | 16 f64 world_from_scan
//             (column-major) | u8 has reference, 16 f64 if so | u32 azimuths, f32 x n |
//             u32 elevations, f32 x n | rows*cols x 3 f32 points | rows*cols f32 reflectance |
//             rows*cols u8 valid | u64 checksum of the record before it.
// One scan of a multi-scan file (an E57 of a whole campaign) is read alone: its header and its
// record, each checked, without the others.
// The arrays are contiguous and in Scan's own layout (a future reader may map them). A missing,
// truncated or corrupt entry is detected, logged as a warning and rebuilt from the source — never
// an error; writes are atomic.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"
#include "core/geometry/scan.h"

namespace scanreg::io {

// The key of a source file: a hash of its bytes (read once, ~1 GB/s from the page cache).
Expected<std::uint64_t> SourceFileKey(const std::filesystem::path& file);
// SourceFileKey memoised in cache_dir/source-keys by the file's path, size and modification time,
// so that reopening a project does not read every source file again: a file changed since has
// another size or time and is hashed again. A file modified within the last 2 seconds is not
// memoised (a second write within the file system's time resolution would go unseen).
Expected<std::uint64_t> MemoisedSourceFileKey(const std::filesystem::path& file, const std::filesystem::path& cache_dir);
std::filesystem::path ScanCachePath(const std::filesystem::path& cache_dir, const std::filesystem::path& file,
                                    std::uint64_t key);

std::string SerializeScanCache(const std::vector<Scan>& scans, std::uint64_t key);
// An error says what is wrong (not a cache entry, another file's, truncated, corrupt).
Expected<std::vector<Scan>> ParseScanCache(const std::string& bytes, std::uint64_t key);
// Scan `index` of the entry file alone; *scans_in_entry (optional): how many it holds, once its
// header is read (an index beyond them is a kInvalidArgument error).
Expected<Scan> ReadScanCacheRecord(const std::filesystem::path& entry, std::uint64_t key, int index,
                                   int* scans_in_entry = nullptr);

// The scans of `file` from cache_dir when it holds a valid entry for the file's content, else
// read by io::ReadScanFile and stored there (failing to store is logged, not returned).
// *from_cache (optional) tells which. Errors are those of reading the source file. cache_dir
// empty: no cache. only >= 0: only that scan is needed — from a valid entry it alone is read and
// the file's other scans are returned empty (a source file is read whole either way).
Expected<std::vector<Scan>> ReadScanFileCached(const std::filesystem::path& file,
                                               const std::filesystem::path& cache_dir, ProgressSink& progress,
                                               const CancelToken& cancel, bool* from_cache = nullptr,
                                               int only = -1);

}  // namespace scanreg::io
