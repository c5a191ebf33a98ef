#include "core/common/output_set.h"

namespace scanreg {

OutputSet::~OutputSet() {
  if (!complete_) Abandon();
}

void OutputSet::Track(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) {
    ++replaced_;
  } else {
    created_.push_back(path);
  }
}

int OutputSet::Abandon() {
  int removed = 0;
  for (const std::filesystem::path& p : created_) {
    std::error_code ec;
    removed += std::filesystem::remove(p, ec) ? 1 : 0;
  }
  created_.clear();
  return removed;
}

Error OutputSet::Failed(Error error) {
  const int replaced = replaced_;
  const int removed = Abandon();
  complete_ = true;  // already cleaned up
  if (removed > 0) error.message += "; removed the " + std::to_string(removed) + " new file(s) written before the error";
  if (replaced > 0) {
    error.message += "; " + std::to_string(replaced) +
                     " file(s) that existed before may already hold this run's output";
  }
  return error;
}

}  // namespace scanreg
