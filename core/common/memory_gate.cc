#include "core/common/memory_gate.h"

#include <cstdio>

namespace scanreg {

std::string FormatBytes(std::size_t bytes) {
  char buf[32];
  if (bytes >= (std::size_t(1) << 30)) {
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / double(1 << 30));
  } else {
    std::snprintf(buf, sizeof buf, "%.0f MB", bytes / double(1 << 20));
  }
  return buf;
}


MemoryGate::Hold::Hold(MemoryGate& gate, std::size_t bytes) : gate_(gate), bytes_(bytes) {
  std::unique_lock<std::mutex> lock(gate_.mutex_);
  gate_.released_.wait(lock, [&] { return gate_.holders_ == 0 || gate_.held_ + bytes_ <= gate_.budget_; });
  gate_.held_ += bytes_;
  ++gate_.holders_;
}

MemoryGate::Hold::~Hold() {
  {
    std::lock_guard<std::mutex> lock(gate_.mutex_);
    gate_.held_ -= bytes_;
    --gate_.holders_;
  }
  gate_.released_.notify_all();
}

std::size_t MemoryGate::held() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return held_;
}

}  // namespace scanreg
