#include "core/common/memory_gate.h"

namespace scanreg {

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
