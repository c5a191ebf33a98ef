#include "core/registration/visibility.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <unordered_map>

#include <Eigen/SVD>

namespace scanreg {
namespace {

// Maps a point (observer frame) to a grid cell; false outside the grid or when the grid's viewing
// geometry is unknown. Two kinds of grid: panoramic (a TLS scan: columns are azimuths, rows
// elevations, scan.angles) and perspective (a depth camera, an organized cloud from one: the
// pixel is a projective map of the direction, (col, row, 1) ~ H p, in any orientation of the
// camera's frame). The perspective map is fitted to the grid's own points (direct linear
// transform); a grid neither panoramic nor perspective (a triangulation scanner's range grid) has
// no viewing geometry here, and free space is not tested against it; nor has a cloud seen from
// several places (Scan::single_viewpoint false).
class GridProjector {
 public:
  explicit GridProjector(const Scan& scan) : scan_(scan) {
    if (scan.rows < 3 || scan.cols < 3) return;
    if (!scan.single_viewpoint) return;  // a cloud seen from several places: its origin saw no free space
    if (!scan.angles.empty()) {
      const auto& az = scan.angles.azimuth;
      const auto& el = scan.angles.elevation;
      az0_ = az.front();
      daz_ = (az.back() - az.front()) / (scan.cols - 1);
      el0_ = el.front();
      del_ = (el.back() - el.front()) / (scan.rows - 1);
      wraps_ = std::abs(daz_ * scan.cols) > 2 * M_PI * 0.97;
      kind_ = Kind::kPanoramic;
    } else if (FitPerspective()) {
      kind_ = Kind::kPerspective;
    }
  }

  bool known() const { return kind_ != Kind::kNone; }
  // The columns close a full circle (a panorama's last column neighbours its first).
  bool wraps() const { return kind_ == Kind::kPanoramic && wraps_; }

  bool Project(const Eigen::Vector3d& p, int* row, int* col) const {
    if (kind_ == Kind::kPerspective) return ProjectPerspective(p, row, col);
    if (kind_ != Kind::kPanoramic) return false;
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
  enum class Kind { kNone, kPanoramic, kPerspective };

  bool ProjectPerspective(const Eigen::Vector3d& p, int* row, int* col) const {
    const Eigen::Vector3d h = h_ * p;
    if (!(h.z() > 1e-12 * p.norm())) return false;  // behind the camera
    const long ci = std::lround(h.x() / h.z()), ri = std::lround(h.y() / h.z());
    if (ri < 0 || ri >= scan_.rows || ci < 0 || ci >= scan_.cols) return false;
    *row = static_cast<int>(ri);
    *col = static_cast<int>(ci);
    return true;
  }

  // Fits h_ to the valid cells of a sub-grid (about 60 x 60) and keeps it when every sample lies in
  // front and the RMS reprojection error is under a quarter of a cell: only a true pinhole grid.
  bool FitPerspective() {
    const int step = std::max(1, std::max(scan_.rows, scan_.cols) / 60);
    std::vector<Eigen::Vector3d> dirs;
    std::vector<Eigen::Vector2d> cells;
    for (int r = 0; r < scan_.rows; r += step)
      for (int c = 0; c < scan_.cols; c += step)
        if (scan_.IsValid(r, c) && scan_.Point(r, c).norm() > 0.0f) {
          dirs.push_back(scan_.Point(r, c).cast<double>().normalized());
          cells.emplace_back(c, r);
        }
    if (dirs.size() < 50) return false;
    // Pixels scaled to about [-1, 1] for conditioning (Hartley normalisation).
    const double s = 2.0 / std::max(scan_.rows, scan_.cols);
    const Eigen::Vector2d centre(0.5 * (scan_.cols - 1), 0.5 * (scan_.rows - 1));
    Eigen::MatrixXd a(2 * dirs.size(), 9);
    for (std::size_t i = 0; i < dirs.size(); ++i) {
      const Eigen::Vector2d u = s * (cells[i] - centre);
      const Eigen::RowVector3d d = dirs[i].transpose();
      a.row(2 * i) << d, Eigen::RowVector3d::Zero(), -u.x() * d;
      a.row(2 * i + 1) << Eigen::RowVector3d::Zero(), d, -u.y() * d;
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
    const Eigen::VectorXd v = svd.matrixV().col(8);
    Eigen::Matrix3d hn;
    hn << v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7), v(8);
    // Back to pixels: u_pix = u / s + centre.
    Eigen::Matrix3d denorm;
    denorm << 1.0 / s, 0, centre.x(), 0, 1.0 / s, centre.y(), 0, 0, 1;
    h_ = denorm * hn;
    int front = 0;
    for (const Eigen::Vector3d& d : dirs) front += (h_ * d).z() > 0 ? 1 : -1;
    if (front < 0) h_ = -h_;
    double sum = 0.0;
    for (std::size_t i = 0; i < dirs.size(); ++i) {
      const Eigen::Vector3d h = h_ * dirs[i];
      if (!(h.z() > 0)) return false;
      sum += (h.head<2>() / h.z() - cells[i]).squaredNorm();
    }
    return std::sqrt(sum / dirs.size()) < 0.25;
  }

  const Scan& scan_;
  Kind kind_ = Kind::kNone;
  double az0_ = 0, daz_ = 0, el0_ = 0, del_ = 0;
  bool wraps_ = false;
  Eigen::Matrix3d h_ = Eigen::Matrix3d::Zero();
};

// The nearest return of the observer's 3x3 cells around q's projection; false when q does not
// project onto a valid cell.
bool NearestAround(const Scan& observer, const GridProjector& projector, const Eigen::Vector3d& q, double* nearest) {
  int row = 0, col = 0;
  if (!projector.Project(q, &row, &col) || !observer.IsValid(row, col)) return false;
  double best = std::numeric_limits<double>::infinity();
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      const int r = row + dr;
      int c = col + dc;
      if (projector.wraps()) c = (c + observer.cols) % observer.cols;
      if (r < 0 || r >= observer.rows || c < 0 || c >= observer.cols || !observer.IsValid(r, c)) continue;
      best = std::min(best, double(observer.Point(r, c).norm()));
    }
  }
  *nearest = best;
  return true;
}

// True when a grid neighbour's range differs by more than `jump` + 2 % of the range: the cell lies on
// a depth edge, where mixed pixels float between the surfaces (in anyone's free space).
bool AtDepthEdge(const Scan& scan, int r, int c, double jump) {
  const double range = scan.Point(r, c).norm();
  const int nb[4][2] = {{r - 1, c}, {r + 1, c}, {r, c - 1}, {r, c + 1}};
  for (const auto& [nr, nc0] : nb) {
    const int nc = (nc0 + scan.cols) % scan.cols;
    if (nr < 0 || nr >= scan.rows || !scan.IsValid(nr, nc)) continue;
    if (std::abs(scan.Point(nr, nc).norm() - range) > jump + 0.02 * range) return true;
  }
  return false;
}

// Indices of `other`'s valid points to test: every k-th row and column of an organized scan (so the
// samples cover surfaces evenly in both directions) away from depth edges, evenly spaced indices
// otherwise. `stride` receives the sub-grid's step (0 for a list). Ascending indices either way.
std::vector<std::size_t> SampleIndicesAll(const Scan& other, int max_samples, double edge_jump, int* stride) {
  std::size_t valid = 0;
  for (std::size_t i = 0; i < other.size(); ++i) valid += other.valid[i] ? 1 : 0;
  const std::size_t wanted = static_cast<std::size_t>(std::max(max_samples, 1));
  std::vector<std::size_t> out;
  if (other.rows > 1 && other.cols > 1) {
    const int k = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(valid) / double(wanted)))));
    *stride = k;
    for (int r = 0; r < other.rows; r += k)
      for (int c = 0; c < other.cols; c += k)
        if (other.IsValid(r, c) && !AtDepthEdge(other, r, c, edge_jump)) out.push_back(other.Index(r, c));
    return out;
  }
  *stride = 0;
  const double step = std::max(1.0, double(valid) / double(wanted));
  double next = 0.0;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < other.size(); ++i) {
    if (!other.valid[i]) continue;
    if (double(seen++) >= next) {
      out.push_back(i);
      next += step;
    }
  }
  return out;
}

// Sample indices without the near field (FreeSpaceOptions::near_field_m).
std::vector<std::size_t> SampleIndices(const Scan& other, const FreeSpaceOptions& options, int* stride) {
  std::vector<std::size_t> all = SampleIndicesAll(other, options.max_samples, options.margin_m, stride);
  if (all.empty()) return all;
  std::vector<float> ranges;
  ranges.reserve(all.size());
  for (std::size_t i : all) ranges.push_back(other.points[i].norm());
  std::vector<float> sorted = ranges;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double near = std::min(options.near_field_m, options.near_field_fraction * sorted[sorted.size() / 2]);
  std::vector<std::size_t> out;
  out.reserve(all.size());
  for (std::size_t k = 0; k < all.size(); ++k)
    if (ranges[k] >= near) out.push_back(all[k]);
  return out;
}

// Connected clusters of points on a grid of `cell` metres (cells touching in 3D join): returns each
// point's cluster and fills the clusters' bounding boxes.
std::vector<int> Cluster(const std::vector<Eigen::Vector3d>& points, double cell,
                         std::vector<Eigen::AlignedBox3d>* boxes) {
  struct KeyHash {
    std::size_t operator()(const Eigen::Vector3i& k) const {
      return (std::size_t(k.x()) * 73856093u) ^ (std::size_t(k.y()) * 19349663u) ^ (std::size_t(k.z()) * 83492791u);
    }
  };
  struct KeyEq {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  std::unordered_map<Eigen::Vector3i, int, KeyHash, KeyEq> cells;
  std::vector<int> cell_of(points.size());
  std::vector<Eigen::Vector3i> keys;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3i key = (points[i] / cell).array().floor().cast<int>();
    auto [it, added] = cells.emplace(key, static_cast<int>(keys.size()));
    if (added) keys.push_back(key);
    cell_of[i] = it->second;
  }
  std::vector<int> parent(keys.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (std::size_t c = 0; c < keys.size(); ++c) {
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = cells.find(keys[c] + Eigen::Vector3i(dx, dy, dz));
          if (it != cells.end()) parent[find(static_cast<int>(c))] = find(it->second);
        }
  }
  std::vector<int> id(keys.size(), -1), cluster(points.size());
  boxes->clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const int root = find(cell_of[i]);
    if (id[root] < 0) {
      id[root] = static_cast<int>(boxes->size());
      boxes->emplace_back();
      boxes->back().setEmpty();
    }
    cluster[i] = id[root];
    (*boxes)[id[root]].extend(points[i]);
  }
  return cluster;
}

// How a cluster of violations meets the rest of `other`'s range image (organized scans, sampled every
// `stride` cells by SampleIndices; nothing for a list). Per
// violating sample and grid direction whose neighbouring sample is not in its cluster, the cells
// between them are walked: a cell with no return, or one farther by a depth jump, is a silhouette
// (the cluster stands in front of what lies behind it, as a vehicle or a person does); a surface
// that runs on without a farther jump into a sample on the observer's own surface is attached (the cluster
// is part of a larger static surface: a corridor's end wall meets its side walls, a shifted façade
// runs on into the façade). Directions into untested samples say nothing.
struct ClusterBoundary {
  int silhouette = 0, attached = 0;
};

std::vector<ClusterBoundary> ClusterBoundaries(const Scan& other, const std::vector<std::size_t>& samples, int stride,
                                               const std::vector<std::uint8_t>& state, const std::vector<int>& cluster_of_sample,
                                               int clusters, double jump) {
  std::vector<ClusterBoundary> out(clusters);
  if (stride < 1) return out;
  const auto sample_at = [&samples](std::size_t cell) {  // the sample on that cell, or -1 (samples ascend)
    const auto it = std::lower_bound(samples.begin(), samples.end(), cell);
    return it != samples.end() && *it == cell ? static_cast<int>(it - samples.begin()) : -1;
  };
  const int dirs[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (state[k] != 2) continue;
    const int cl = cluster_of_sample[k];
    const int r0 = static_cast<int>(samples[k] / other.cols), c0 = static_cast<int>(samples[k] % other.cols);
    for (const auto& d : dirs) {
      const int nr = r0 + d[0] * stride;
      if (nr < 0 || nr >= other.rows) continue;
      const int nc = ((c0 + d[1] * stride) % other.cols + other.cols) % other.cols;
      const int neighbour = sample_at(other.Index(nr, nc));
      if (neighbour >= 0 && state[neighbour] == 2 && cluster_of_sample[neighbour] == cl) continue;
      double previous = other.points[samples[k]].norm();
      bool silhouette = false;
      for (int step = 1; step <= stride && !silhouette; ++step) {
        const int r = r0 + d[0] * step, c = ((c0 + d[1] * step) % other.cols + other.cols) % other.cols;
        if (!other.IsValid(r, c)) {
          silhouette = true;
          break;
        }
        const double range = other.Point(r, c).norm();
        silhouette = range > previous + jump + 0.02 * previous;
        previous = range;
      }
      if (silhouette) {
        ++out[cl].silhouette;
      } else if (neighbour >= 0 && state[neighbour] == 3) {
        ++out[cl].attached;
      }
    }
  }
  return out;
}

}  // namespace

FreeSpaceResult FreeSpaceViolations(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                                    const FreeSpaceOptions& options, const RayFreeSpace* observer_rays) {
  FreeSpaceResult result;
  const GridProjector projector(observer);
  const bool rays = !projector.known() && observer_rays && observer_rays->known();
  if (!projector.known() && !rays) return result;
  int stride = 0;
  const std::vector<std::size_t> samples = SampleIndices(other, options, &stride);
  std::vector<std::uint8_t> state(samples.size(), 0);  // 1 tested (behind), 2 violation, 3 on the observer's surface
  std::vector<Eigen::Vector3d> mapped(samples.size());  // in the observer's frame
#pragma omp parallel for schedule(static)
  for (long k = 0; k < static_cast<long>(samples.size()); ++k) {
    const Eigen::Vector3d q = mapped[k] = observer_from_other * other.points[samples[k]].cast<double>();
    if (rays) {
      const RayFreeSpace::Seen seen = observer_rays->At(q);
      state[k] = seen == RayFreeSpace::Seen::kFree ? 2 : seen == RayFreeSpace::Seen::kSurface ? 3 : 0;
      continue;
    }
    double nearest = 0.0;
    if (!NearestAround(observer, projector, q, &nearest)) continue;
    state[k] = nearest > q.norm() + options.margin_m ? 2 : nearest >= q.norm() - options.margin_m ? 3 : 1;
  }
  std::vector<Eigen::Vector3d> violating;
  std::vector<std::size_t> violating_sample;
  Eigen::AlignedBox3d extent;
  extent.setEmpty();
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (!state[k]) continue;
    const Eigen::Vector3d& q = mapped[k];
    extent.extend(q);
    ++result.tested;
    if (state[k] == 2) violating.push_back(q), violating_sample.push_back(k);
  }
  result.violations = static_cast<int>(violating.size());
  if (violating.empty() || !(options.cluster_cell_m > 0.0)) return result;
  std::vector<Eigen::AlignedBox3d> boxes;
  const std::vector<int> cluster = Cluster(violating, options.cluster_cell_m, &boxes);
  std::vector<int> cluster_of_sample(samples.size(), -1);
  for (std::size_t v = 0; v < violating_sample.size(); ++v) cluster_of_sample[violating_sample[v]] = cluster[v];
  const std::vector<ClusterBoundary> boundary =
      ClusterBoundaries(other, samples, stride, state, cluster_of_sample, static_cast<int>(boxes.size()), options.margin_m);
  const double max_size = std::min(options.max_object_m, options.max_object_share * extent.diagonal().norm());
  for (int c : cluster) {
    const bool attached = boundary[c].attached >= std::max(2, boundary[c].silhouette);
    result.moving += boxes[c].diagonal().norm() <= max_size && !attached ? 1 : 0;
  }
  if (result.moving_fraction() > options.max_moving) result.moving = 0;  // not traffic: everything moved
  return result;
}

bool HasViewpoint(const Scan& observer) { return GridProjector(observer).known(); }

PairFreeSpace PairFreeSpaceCheck(const Scan& a, const Scan& b, const Eigen::Isometry3d& a_from_b,
                                 const FreeSpaceOptions& options, const RayFreeSpace* a_rays,
                                 const RayFreeSpace* b_rays) {
  PairFreeSpace r;
  r.a_sees_b = FreeSpaceViolations(a, b, a_from_b, options, a_rays);
  r.b_sees_a = FreeSpaceViolations(b, a, a_from_b.inverse(), options, b_rays);
  return r;
}

void MarkFreeSpacePoints(const Scan& observer, const Scan& other, const Eigen::Isometry3d& observer_from_other,
                         double margin_m, std::vector<std::uint8_t>* mask, const RayFreeSpace* observer_rays) {
  mask->resize(other.size(), 0);
  const GridProjector projector(observer);
  const bool rays = !projector.known() && observer_rays && observer_rays->known();
  if (!projector.known() && !rays) return;
  std::vector<std::uint8_t>& m = *mask;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(other.size()); ++i) {
    if (!other.valid[i] || m[i]) continue;
    const Eigen::Vector3d q = observer_from_other * other.points[i].cast<double>();
    if (rays) {
      if (observer_rays->Free(q)) m[i] = 1;
      continue;
    }
    double nearest = 0.0;
    if (NearestAround(observer, projector, q, &nearest) && nearest > q.norm() + margin_m) m[i] = 1;
  }
}

}  // namespace scanreg
