// Dense point-to-plane ICP (Chen & Medioni 1992) with a Tukey kernel, KISS-ICP style: one
// Gauss-Newton step per iteration on voxel-downsampled points, OpenMP over the child samples.
#include <omp.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <string>

#include "core/registration/icp.h"
#include "core/registration/point_index.h"
#include "core/registration/voxel_filter.h"

namespace scanreg {
namespace {

// PCA normal over the k nearest samples of point i; zero vector where the neighbourhood is not planar.
Eigen::Vector3d PcaNormal(const std::vector<Eigen::Vector3d>& pts, const PointIndex& index, long i, int k,
                          double max_variation) {
  const std::vector<int> nn = index.KNearest(pts[i], k);
  if (nn.size() < 5) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int j : nn) mean += pts[j];
  mean /= static_cast<double>(nn.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int j : nn) cov += (pts[j] - mean) * (pts[j] - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  const double total = ev.sum();
  if (!(total > 0.0) || ev(0) / total > max_variation) return Eigen::Vector3d::Zero();
  return eig.eigenvectors().col(0);
}

struct Pairing {
  int target = -1;  // parent sample, -1 when none within the distance
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // the target's
  double residual = 0.0;  // n . (T p - s), metres
};

double MedianAbs(std::vector<double> v) {
  if (v.empty()) return 0.0;
  for (double& x : v) x = std::abs(x);
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

Status DenseIcpOptions::Validate() const {
  auto bad = [](const std::string& m) { return Status(MakeError(ErrorCode::kInvalidArgument, "dense ICP: " + m)); };
  if (!(voxel_m >= 0.0) || !std::isfinite(voxel_m)) return bad("voxel_m must be >= 0 metres");
  if (normal_neighbours < 5) return bad("normal_neighbours must be >= 5");
  if (!(max_surface_variation > 0.0 && max_surface_variation <= 1.0 / 3.0))
    return bad("max_surface_variation must be in (0, 1/3]");
  if (max_correspondence_schedule_m.empty()) return bad("max_correspondence_schedule_m needs at least one distance");
  for (double d : max_correspondence_schedule_m)
    if (!(d > 0.0) || !std::isfinite(d)) return bad("every correspondence distance must be > 0 metres");
  if (max_iterations_per_stage < 1) return bad("max_iterations_per_stage must be >= 1");
  if (!(convergence_translation_m >= 0.0) || !(convergence_rotation_rad >= 0.0)) return bad("convergence thresholds must be >= 0");
  if (!(robust_scale_floor_m > 0.0)) return bad("robust_scale_floor_m must be > 0 metres");
  if (min_correspondences < 6) return bad("min_correspondences must be >= 6 (6 unknowns)");
  if (max_samples < min_correspondences) return bad("max_samples must be >= min_correspondences");
  return Status::Ok();
}

Expected<IcpResult> DenseIcp(const Scan& parent, const Scan& child, Eigen::Isometry3d initial_parent_from_child,
                             const DenseIcpOptions& options, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (Status s = parent.Validate(); !s) return s.error();
  if (Status s = child.Validate(); !s) return s.error();
  const std::vector<Eigen::Vector3d> target = VoxelDownsample(ValidPoints(parent), options.voxel_m);
  const std::vector<Eigen::Vector3d> source = VoxelDownsample(ValidPoints(child), options.voxel_m);
  if (target.empty() || source.empty())
    return MakeError(ErrorCode::kInvalidArgument, "dense ICP: scan '" + (target.empty() ? parent.name : child.name) +
                                                      "' has no valid points");
  return DenseIcpSamples(target, source, initial_parent_from_child, options, progress, cancel);
}

Expected<IcpResult> DenseIcpSamples(const std::vector<Eigen::Vector3d>& parent_samples,
                                    const std::vector<Eigen::Vector3d>& child_samples,
                                    Eigen::Isometry3d initial_parent_from_child, const DenseIcpOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (parent_samples.empty() || child_samples.empty())
    return MakeError(ErrorCode::kInvalidArgument, "dense ICP: a scan has no valid points");
  return DenseIcpSurface(IcpSurface(parent_samples, options), child_samples, initial_parent_from_child, options,
                         progress, cancel);
}

IcpSurface::IcpSurface(std::vector<Eigen::Vector3d> samples, const DenseIcpOptions& options)
    : points(std::move(samples)),
      index(std::make_unique<PointIndex>(points)),
      normal_neighbours_(options.normal_neighbours),
      max_surface_variation_(options.max_surface_variation),
      normals_(points.size(), Eigen::Vector3d::Zero()),
      normal_state_(std::make_unique<std::atomic<std::uint8_t>[]>(points.size())) {
  for (std::size_t i = 0; i < points.size(); ++i) normal_state_[i].store(0, std::memory_order_relaxed);
}

IcpSurface::~IcpSurface() = default;

std::size_t IcpSurface::Bytes() const {
  return (points.capacity() + normals_.capacity()) * sizeof(Eigen::Vector3d) + points.size() +
         (index ? index->Bytes() : 0);
}

Eigen::Vector3d IcpSurface::Normal(int sample) const {
  std::atomic<std::uint8_t>& state = normal_state_[sample];
  if (state.load(std::memory_order_acquire) == 2) return normals_[sample];
  // Two threads may both compute it (the same value); one stores it.
  const Eigen::Vector3d n = PcaNormal(points, *index, sample, normal_neighbours_, max_surface_variation_);
  std::uint8_t expected = 0;
  if (state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
    normals_[sample] = n;
    state.store(2, std::memory_order_release);
  }
  return n;
}

Expected<IcpResult> DenseIcpSurface(const IcpSurface& parent, const std::vector<Eigen::Vector3d>& child_samples,
                                    Eigen::Isometry3d initial_parent_from_child, const DenseIcpOptions& options,
                                    ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  if (parent.points.empty() || child_samples.empty())
    return MakeError(ErrorCode::kInvalidArgument, "dense ICP: a scan has no valid points");
  const std::vector<Eigen::Vector3d>& target = parent.points;
  const std::vector<Eigen::Vector3d> source = ThinEvenly(child_samples, options.max_samples);
  const PointIndex& index = *parent.index;

  IcpResult out;
  out.parent_from_child = initial_parent_from_child;
  const long n = static_cast<long>(source.size());
  std::vector<Pairing> pairs(n);
  const int stages = static_cast<int>(options.max_correspondence_schedule_m.size());

  // Pairs every child sample with its nearest parent sample within max_d (having a normal).
  auto pair_all = [&](double max_d) {
#pragma omp parallel for schedule(dynamic, 512)
    for (long i = 0; i < n; ++i) {
      const Eigen::Vector3d q = out.parent_from_child * source[i];
      const int j = index.Nearest(q, max_d);
      pairs[i] = Pairing{};
      const Eigen::Vector3d normal = j < 0 ? Eigen::Vector3d::Zero() : parent.Normal(j);
      if (normal.isZero()) {
        pairs[i].target = j < 0 ? -1 : -2;  // -2: within reach but no normal (counts for overlap)
        continue;
      }
      pairs[i].target = j;
      pairs[i].normal = normal;
      pairs[i].residual = normal.dot(q - target[j]);
    }
  };

  for (int stage = 0; stage < stages; ++stage) {
    const double max_d = options.max_correspondence_schedule_m[stage];
    out.converged = false;
    for (int it = 0; it < options.max_iterations_per_stage; ++it) {
      if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "dense ICP cancelled");
      progress.Report((stage + double(it) / options.max_iterations_per_stage) / stages, "dense ICP");
      pair_all(max_d);
      std::vector<double> residuals;
      for (const Pairing& p : pairs)
        if (p.target >= 0) residuals.push_back(p.residual);
      out.correspondences = static_cast<int>(residuals.size());
      if (out.correspondences < options.min_correspondences) break;
      // Coarse stages keep residuals up to about half their reach (floor: a tenth of it): a start
      // a few decimetres off along a street is corrected only by the few surfaces across it, whose
      // residuals the noise-sized scale would reject (issue 11, plan-view starts).
      const double floor =
          stage + 1 < stages ? std::max(options.robust_scale_floor_m, 0.1 * max_d) : options.robust_scale_floor_m;
      const double scale = std::max(1.4826 * MedianAbs(residuals), floor);
      const double c = 4.685 * scale;  // Tukey biweight
      // Gauss-Newton normal equations, x = [omega; v], left perturbation T <- exp(x) T:
      // r = n . (q - s), dr/domega = (q x n)^T, dr/dv = n^T.
      const int threads = omp_get_max_threads();
      std::vector<Eigen::Matrix<double, 6, 6>> h_part(threads, Eigen::Matrix<double, 6, 6>::Zero());
      std::vector<Eigen::Matrix<double, 6, 1>> g_part(threads, Eigen::Matrix<double, 6, 1>::Zero());
#pragma omp parallel num_threads(threads)
      {
        const int t = omp_get_thread_num();
        Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
        Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
#pragma omp for schedule(static)
        for (long i = 0; i < n; ++i) {
          const Pairing& p = pairs[i];
          if (p.target < 0 || std::abs(p.residual) >= c) continue;
          const double u = p.residual / c;
          const double w = (1.0 - u * u) * (1.0 - u * u);
          const Eigen::Vector3d q = out.parent_from_child * source[i];
          const Eigen::Vector3d& nrm = p.normal;
          Eigen::Matrix<double, 6, 1> j;
          j << q.cross(nrm), nrm;
          h += w * j * j.transpose();
          g += w * j * p.residual;
        }
        h_part[t] = h;
        g_part[t] = g;
      }
      Eigen::Matrix<double, 6, 6> h = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
      for (int t = 0; t < threads; ++t) {
        h += h_part[t];
        g += g_part[t];
      }
      const Eigen::Matrix<double, 6, 1> x = h.ldlt().solve(-g);
      if (!x.allFinite()) break;
      const Eigen::Vector3d omega = x.head<3>();
      Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
      if (omega.norm() > 0.0) step.linear() = Eigen::AngleAxisd(omega.norm(), omega.normalized()).toRotationMatrix();
      step.translation() = x.tail<3>();
      out.parent_from_child = step * out.parent_from_child;
      ++out.iterations;
      if (x.tail<3>().norm() < options.convergence_translation_m && omega.norm() < options.convergence_rotation_rad) {
        out.converged = true;
        break;
      }
    }
  }

  // Final statistics at the final pose, with the last (finest) distance.
  pair_all(options.max_correspondence_schedule_m.back());
  double sum2 = 0.0;
  int used = 0, reached = 0;
  for (const Pairing& p : pairs) {
    if (p.target == -1) continue;
    ++reached;
    if (p.target >= 0) {
      sum2 += p.residual * p.residual;
      ++used;
    }
  }
  out.correspondences = used;
  out.rms_m = used ? std::sqrt(sum2 / used) : 0.0;
  out.overlap = static_cast<double>(reached) / n;
  if (used < options.min_correspondences) out.converged = false;
  progress.Report(1.0, "dense ICP");
  return out;
}

}  // namespace scanreg
