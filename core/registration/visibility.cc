#include "core/registration/visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace scanreg {
namespace {

// Maps a direction to a grid cell of a scan with a regular angular grid; false outside it.
class GridProjector {
 public:
  explicit GridProjector(const Scan& scan) : scan_(scan) {
    const auto& az = scan.angles.azimuth;
    const auto& el = scan.angles.elevation;
    az0_ = az.front();
    daz_ = (az.back() - az.front()) / (scan.cols - 1);
    el0_ = el.front();
    del_ = (el.back() - el.front()) / (scan.rows - 1);
    wraps_ = std::abs(daz_ * scan.cols) > 2 * M_PI * 0.97;
  }

  bool Project(const Eigen::Vector3d& p, int* row, int* col) const {
    const double az = std::atan2(p.y(), p.x());
    const double el = std::atan2(p.z(), std::hypot(p.x(), p.y()));
    double da = std::remainder(az - az0_, 2 * M_PI);
    double c = da / daz_;
    if (wraps_) c = std::fmod(c + 2.0 * scan_.cols, double(scan_.cols));
    const double r = (el - el0_) / del_;
    const long ci = std::lround(c), ri = std::lround(r);
    if (ri < 0 || ri >= scan_.rows) return false;
    if (ci < 0 || ci >= scan_.cols) {
      if (!wraps_) return false;
    }
    *row = static_cast<int>(ri);
    *col = static_cast<int>(((ci % scan_.cols) + scan_.cols) % scan_.cols);
    return true;
  }

 private:
  const Scan& scan_;
  double az0_, daz_, el0_, del_;
  bool wraps_;
};

}  // namespace

FreeSpaceResult FreeSpaceViolations(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                                    double margin_m, int max_samples) {
  FreeSpaceResult result;
  if (observer.angles.empty() || observer.rows < 3 || observer.cols < 3) return result;
  const GridProjector projector(observer);
  std::vector<std::size_t> valid;
  valid.reserve(other.size());
  for (std::size_t i = 0; i < other.size(); ++i)
    if (other.valid[i]) valid.push_back(i);
  const std::size_t n = std::min<std::size_t>(valid.size(), static_cast<std::size_t>(std::max(max_samples, 1)));
  const double stride = n ? double(valid.size()) / n : 1.0;
  int tested = 0, violations = 0;
#pragma omp parallel for reduction(+ : tested, violations) schedule(static)
  for (long k = 0; k < static_cast<long>(n); ++k) {
    const Eigen::Vector3d q = observer_from_other * other.points[valid[static_cast<std::size_t>(k * stride)]].cast<double>();
    int row = 0, col = 0;
    if (!projector.Project(q, &row, &col) || !observer.IsValid(row, col)) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (int dr = -1; dr <= 1; ++dr) {
      for (int dc = -1; dc <= 1; ++dc) {
        const int r = row + dr;
        const int c = (col + dc + observer.cols) % observer.cols;
        if (r < 0 || r >= observer.rows || !observer.IsValid(r, c)) continue;
        nearest = std::min(nearest, double(observer.Point(r, c).norm()));
      }
    }
    ++tested;
    if (nearest > q.norm() + margin_m) ++violations;
  }
  result.tested = tested;
  result.violations = violations;
  return result;
}

}  // namespace scanreg
