#include "core/common/allocator.h"

#include <malloc.h>

namespace scanreg {

void ReuseFreedMemory() {
  constexpr int kMmapThreshold = 64 << 20;
  constexpr int kTrimThreshold = 128 << 20;
  mallopt(M_MMAP_THRESHOLD, kMmapThreshold);
  mallopt(M_TRIM_THRESHOLD, kTrimThreshold);
}

}  // namespace scanreg
