// On-disk cache of SIFT features beside a project, so that a re-run skips detection (issue 3,
// step 1). Entries are keyed by a hash of the scan's content and of the SIFT options; a missing,
// truncated or corrupt entry is detected, logged as a warning and re-detected — never an error.
//
// File format (native little-endian), one file per entry, "<cache_dir>/sift_<16 hex key>.feat":
//   char[8] magic "SRGFEAT\0" | u32 version | u32 descriptor size (128) | u64 key |
//   i32 rows | i32 cols | u64 n | n x {f32 u, v, size, angle, response} | n x 128 f32 |
//   u64 checksum of everything after the header
// Written to a temporary file in cache_dir and renamed over the entry (readers never see a
// partial file).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "core/common/expected.h"
#include "core/features/sift.h"
#include "core/geometry/scan.h"

namespace scanreg {

// 64-bit hash of rows, cols, points, reflectance and valid flags (not the name or pose).
std::uint64_t ScanContentHash(const Scan& scan);

// The cache key of (scan content, options, detector version) and the entry's path.
std::uint64_t FeatureCacheKey(const Scan& scan, const SiftOptions& options);
std::filesystem::path FeatureCachePath(const Scan& scan, const SiftOptions& options,
                                       const std::filesystem::path& cache_dir);

// Parses the bytes of a cache entry for `scan` under `key`; an error says what is wrong (truncated,
// another scan's entry, corrupt). Exposed for the fuzz harness (tests/fuzz).
Expected<ScanFeatures> ParseFeatureCacheEntry(const std::string& bytes, std::uint64_t key, const Scan& scan);

// Returns the cached features of (scan, options) if cache_dir holds a valid entry, else runs
// DetectFeatures and stores the result (cache_dir is created if missing; failing to write the cache
// is logged, not returned). *from_cache (optional) tells which happened. Errors are those of
// DetectFeatures (bad options or scan). Safe to call in parallel for different scans.
Expected<ScanFeatures> LoadOrDetectFeatures(const Scan& scan, const SiftOptions& options,
                                            const std::filesystem::path& cache_dir, bool* from_cache = nullptr);

}  // namespace scanreg
