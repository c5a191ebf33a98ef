// Work that needs much memory for a while (SIFT's image pyramids on a large panorama) run side by
// side only while their estimated bytes fit a budget; one always runs, whatever its size.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>

namespace scanreg {

// A memory size as the options take it (binary units: 1 GB = 2^30 bytes): "1.2 GB", "850 MB".
std::string FormatBytes(std::size_t bytes);

class MemoryGate {
 public:
  explicit MemoryGate(std::size_t budget_bytes) : budget_(budget_bytes) {}

  // Waits until `bytes` fit beside what is held (or nothing is held), then holds them until destroyed.
  class Hold {
   public:
    Hold(MemoryGate& gate, std::size_t bytes);
    ~Hold();
    Hold(const Hold&) = delete;
    Hold& operator=(const Hold&) = delete;

   private:
    MemoryGate& gate_;
    std::size_t bytes_;
  };

  std::size_t held() const;

 private:
  const std::size_t budget_;
  mutable std::mutex mutex_;
  std::condition_variable released_;
  std::size_t held_ = 0;
  int holders_ = 0;
};

}  // namespace scanreg
