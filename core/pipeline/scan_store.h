// Full scans and dense-ICP surfaces on demand under one memory budget (issue 13, item 1). The
// registration keeps per scan only what its pairs use (features, keypoint points, voxel samples:
// register_pair.h). The full scan is needed again only for the free-space test and EM fine
// alignment, and is then read back (from the binary scan cache, io/scan_cache.h) when it is no
// longer resident; a scan's dense-ICP surface (k-d tree and normals of its samples) is built when a
// pair needs it and kept while the budget allows. The least recently used are dropped to stay
// within the budget; one a caller still holds (its shared_ptr) stays alive until released, so the
// resident total can exceed the budget by those in use (two scans and a surface per pair being
// registered).
#pragma once

#include <cstddef>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/common/expected.h"
#include "core/common/memory_gate.h"  // FormatBytes
#include "core/common/progress.h"
#include "core/geometry/scan.h"
#include "core/io/project.h"
#include "core/registration/icp.h"

namespace scanreg::pipeline {

// Bytes a scan holds in memory (its arrays).
std::size_t ScanBytes(const Scan& scan);

// The default budget: a quarter of the machine's physical memory (at least 1 GiB).
std::size_t DefaultMemoryBudget();
// "6G", "800M", "1.5G", "2T" (binary units; a bare number is gigabytes). Errors say what is accepted.
Expected<std::size_t> ParseMemoryBudget(const std::string& text);

class ScanStore {
 public:
  using Reader = std::function<Expected<Scan>(int index)>;
  // Scans read by `read` (by index), named and posed as `heads` say (a head is a Scan without its
  // arrays: name, poses); at most budget_bytes resident beyond the scans in use.
  ScanStore(std::vector<Scan> heads, Reader read, std::size_t budget_bytes);
  // Scans the caller keeps in memory: never read, never dropped (surfaces are kept too).
  explicit ScanStore(const std::vector<Scan>& scans);

  int size() const { return static_cast<int>(heads_.size()); }
  const std::vector<Scan>& heads() const { return heads_; }
  // The full scan, read when not resident. Thread-safe; a scan is read by one caller at a time.
  Expected<std::shared_ptr<const Scan>> Get(int index);
  // Scan `index`'s dense-ICP surface, made by `build` when not resident. Thread-safe; one caller
  // builds a surface at a time.
  std::shared_ptr<const IcpSurface> Surface(int index, const std::function<std::shared_ptr<const IcpSurface>()>& build);

  std::size_t budget_bytes() const { return budget_; }
  int reads() const;                 // scans read so far (the first reads included)
  int surface_builds() const;        // surfaces built so far
  std::size_t peak_bytes() const;    // the most held at once by the store (scans and surfaces)
  // The caller's scans (the second constructor), else null.
  const std::vector<Scan>* in_memory() const { return caller_; }

 private:
  // What the store holds in a slot: scan i in slot i, its surface in slot size() + i.
  struct Made {
    std::shared_ptr<const void> value;
    std::size_t bytes = 0;
  };
  Expected<std::shared_ptr<const void>> Hold(int slot, const std::function<Expected<Made>()>& make);
  void Trim();  // with mutex_ held

  std::vector<Scan> heads_;
  Reader read_;
  std::size_t budget_ = 0;
  const std::vector<Scan>* caller_ = nullptr;
  mutable std::mutex mutex_;
  std::vector<std::shared_ptr<const void>> resident_;  // per slot
  std::vector<std::size_t> bytes_;
  std::list<int> recent_;  // slots, most recently used first
  std::vector<std::unique_ptr<std::mutex>> making_;  // per slot: made by one caller at a time
  std::size_t held_ = 0, peak_ = 0;
  int reads_ = 0, builds_ = 0;
};

// A scan without its arrays: name, grid size and poses.
Scan ScanHead(const Scan& scan);

// The project's scans through a store: each read with LoadProjectScans (from the binary scan cache
// when it holds the file) when asked for. The heads carry the project's names and poses.
ScanStore ProjectScanStore(const io::Project& project, std::size_t budget_bytes);
// Its heads (the project's names and poses) and its reader (the project's scan `index` by
// LoadProjectScans).
std::vector<Scan> ProjectScanHeads(const io::Project& project);
ScanStore::Reader ProjectScanReader(const io::Project& project);

}  // namespace scanreg::pipeline
