#include "core/pipeline/scan_store.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <unistd.h>

#include "core/pipeline/project_scans.h"

namespace scanreg::pipeline {

std::size_t ScanBytes(const Scan& scan) {
  return scan.points.capacity() * sizeof(Eigen::Vector3f) + scan.reflectance.capacity() * sizeof(float) +
         scan.valid.capacity() + (scan.angles.azimuth.capacity() + scan.angles.elevation.capacity()) * sizeof(float) +
         scan.list_points.capacity() * sizeof(Eigen::Vector3f) + scan.list_reflectance.capacity() * sizeof(float) +
         (scan.colour.capacity() + scan.list_colour.capacity()) * sizeof(Rgb) +
         (scan.time.capacity() + scan.list_time.capacity()) * sizeof(double) +
         (scan.sensor.capacity() + scan.list_sensor.capacity()) * sizeof(Eigen::Vector3f);
}

std::size_t DefaultMemoryBudget() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  const std::size_t ram = pages > 0 && page > 0 ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(page) : 0;
  return std::max<std::size_t>(ram / 4, std::size_t(1) << 30);
}

Expected<std::size_t> ParseMemoryBudget(const std::string& text) {
  const auto bad = [&]() -> Error {
    return MakeError(ErrorCode::kInvalidArgument, "memory budget '" + text +
                                                      "' is not a size: give e.g. 6G, 800M or 1.5G (at least 1M)");
  };
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return bad();
  }
  const std::string unit = text.substr(used);
  double scale = 0;
  if (unit.empty() || unit == "G" || unit == "g" || unit == "GB") scale = 1024.0 * 1024 * 1024;
  if (unit == "M" || unit == "m" || unit == "MB") scale = 1024.0 * 1024;
  if (unit == "T" || unit == "t" || unit == "TB") scale = 1024.0 * 1024 * 1024 * 1024;
  const double bytes = value * scale;
  if (!(scale > 0) || !std::isfinite(bytes) || bytes < 1024.0 * 1024 || bytes > 1e18) return bad();
  return static_cast<std::size_t>(bytes);
}


Scan ScanHead(const Scan& scan) {
  Scan head;
  head.name = scan.name;
  head.rows = scan.rows;
  head.cols = scan.cols;
  head.world_from_scan = scan.world_from_scan;
  head.reference_world_from_scan = scan.reference_world_from_scan;
  return head;
}

ScanStore::ScanStore(std::vector<Scan> heads, Reader read, std::size_t budget_bytes)
    : heads_(std::move(heads)), read_(std::move(read)), budget_(budget_bytes) {
  resident_.resize(2 * heads_.size());
  bytes_.assign(2 * heads_.size(), 0);
  for (std::size_t i = 0; i < 2 * heads_.size(); ++i) making_.push_back(std::make_unique<std::mutex>());
}

namespace {
std::vector<Scan> HeadsOf(const std::vector<Scan>& scans) {
  std::vector<Scan> heads;
  for (const Scan& s : scans) heads.push_back(ScanHead(s));
  return heads;
}
}  // namespace

ScanStore::ScanStore(const std::vector<Scan>& scans)
    : ScanStore(HeadsOf(scans), nullptr, std::numeric_limits<std::size_t>::max()) {
  caller_ = &scans;
}

Expected<std::shared_ptr<const void>> ScanStore::Hold(int slot, const std::function<Expected<Made>()>& make) {
  std::lock_guard<std::mutex> one_maker(*making_[slot]);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (resident_[slot]) {
      recent_.remove(slot);
      recent_.push_front(slot);
      return resident_[slot];
    }
  }
  Expected<Made> made = make();  // outside the store's lock: other slots are served meanwhile
  if (!made) return made.error();
  std::lock_guard<std::mutex> lock(mutex_);
  (slot < size() ? reads_ : builds_) += 1;
  resident_[slot] = made->value;
  bytes_[slot] = made->bytes;
  held_ += made->bytes;
  recent_.push_front(slot);
  Trim();
  peak_ = std::max(peak_, held_);
  return made->value;
}

Expected<std::shared_ptr<const Scan>> ScanStore::Get(int index) {
  if (index < 0 || index >= size())
    return MakeError(ErrorCode::kInvalidArgument, "scan number " + std::to_string(index) + " is not in the project");
  if (caller_) return std::shared_ptr<const Scan>(std::shared_ptr<const Scan>(), &(*caller_)[index]);
  const Expected<std::shared_ptr<const void>> held = Hold(index, [&]() -> Expected<Made> {
    Expected<Scan> read = read_(index);
    if (!read) return read.error();
    const Scan& head = heads_[index];
    read->name = head.name;
    read->world_from_scan = head.world_from_scan;
    read->reference_world_from_scan = head.reference_world_from_scan;
    auto scan = std::make_shared<const Scan>(std::move(*read));
    const std::size_t bytes = ScanBytes(*scan);
    return Made{scan, bytes};
  });
  if (!held) return held.error();
  return std::static_pointer_cast<const Scan>(*held);
}

std::shared_ptr<const IcpSurface> ScanStore::Surface(int index,
                                                     const std::function<std::shared_ptr<const IcpSurface>()>& build) {
  if (index < 0 || index >= size()) return nullptr;
  const Expected<std::shared_ptr<const void>> held = Hold(size() + index, [&]() -> Expected<Made> {
    std::shared_ptr<const IcpSurface> surface = build();
    const std::size_t bytes = surface ? surface->Bytes() : 0;
    return Made{surface, bytes};
  });
  return held ? std::static_pointer_cast<const IcpSurface>(*held) : nullptr;
}

void ScanStore::Trim() {
  // Least recently used first; the slot just made (the front) always stays.
  while (held_ > budget_ && recent_.size() > 1) {
    const int i = recent_.back();
    recent_.pop_back();
    held_ -= bytes_[i];
    bytes_[i] = 0;
    resident_[i].reset();  // freed now, or when its last user lets go
  }
}

int ScanStore::reads() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return reads_;
}

int ScanStore::surface_builds() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return builds_;
}

std::size_t ScanStore::peak_bytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return peak_;
}

std::vector<Scan> ProjectScanHeads(const io::Project& project) {
  std::vector<Scan> heads;
  for (const io::ProjectScan& ps : project.scans) {
    Scan head;
    head.name = ps.name;
    head.world_from_scan = ps.world_from_scan;
    head.reference_world_from_scan = ps.reference_world_from_scan;
    heads.push_back(std::move(head));
  }
  return heads;
}

ScanStore ProjectScanStore(const io::Project& project, std::size_t budget_bytes) {
  return ScanStore(ProjectScanHeads(project), ProjectScanReader(project), budget_bytes);
}

ScanStore::Reader ProjectScanReader(const io::Project& project) {
  return [project](int index) -> Expected<Scan> {
    NullProgress quiet;
    Expected<std::vector<Scan>> one = LoadProjectScans(project, quiet, CancelToken(), {index});
    if (!one) return one.error();
    return std::move(one->front());
  };
}

}  // namespace scanreg::pipeline
