#include "core/registration/em_align.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/registration/rigid_fit.h"

namespace scanreg {
namespace {

struct Pair {
  Eigen::Vector3d s;  // sample, child frame
  Eigen::Vector3d x;  // the child vertex it was sampled from
  Eigen::Vector3d y;  // correspondence, parent frame
  double w = 0;
  bool ok = false;
};

// PCA normal of the parent at a cell over a (2k+1)^2 window of grid neighbours, skipping those
// across depth discontinuities. Zero vector when fewer than 3 neighbours.
Eigen::Vector3d WindowNormal(const Scan& s, int row, int col, int k, double break_m) {
  const Eigen::Vector3d c0 = s.Point(row, col).cast<double>();
  double d4 = std::numeric_limits<double>::infinity();
  const int dr4[4] = {-1, 1, 0, 0}, dc4[4] = {0, 0, -1, 1};
  for (int i = 0; i < 4; ++i) {
    const int r = row + dr4[i], c = col + dc4[i];
    if (r >= 0 && r < s.rows && c >= 0 && c < s.cols && s.IsValid(r, c))
      d4 = std::min(d4, (s.Point(r, c).cast<double>() - c0).norm());
  }
  if (!std::isfinite(d4)) return Eigen::Vector3d::Zero();
  const double radius = (k + 1) * std::max(break_m, 8.0 * d4);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
  int n = 0;
  for (int r = std::max(0, row - k); r <= std::min(s.rows - 1, row + k); ++r)
    for (int c = std::max(0, col - k); c <= std::min(s.cols - 1, col + k); ++c) {
      if (!s.IsValid(r, c)) continue;
      const Eigen::Vector3d p = s.Point(r, c).cast<double>();
      if ((p - c0).norm() > radius) continue;
      sum += p;
      sq += p * p.transpose();
      ++n;
    }
  if (n < 3) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d mean = sum / n;
  const Eigen::Matrix3d cov = sq / n - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return eig.eigenvectors().col(0);
}

Eigen::Isometry3d SmallMotion(const Eigen::Matrix<double, 6, 1>& x) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const Eigen::Vector3d w = x.head<3>();
  if (w.norm() > 0) t.linear() = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  t.translation() = x.tail<3>();
  return t;
}

}  // namespace

const char* EmMethodName(EmOptions::Method method) {
  switch (method) {
    case EmOptions::Method::kEm: return "EM";
    case EmOptions::Method::kProjectiveIcp: return "projective ICP [15]";
    case EmOptions::Method::kPointToPlane: return "point-to-plane ICP";
  }
  return "?";
}

std::string EmMethodName(const EmOptions& options) {
  if (options.method != EmOptions::Method::kEm) return EmMethodName(options.method);
  return options.residual == EmOptions::Residual::kPointToPoint ? "EM (S, point-to-point)" : "EM (point-to-plane)";
}

Status EmOptions::Validate() const {
  auto bad = [](const std::string& what) { return MakeError(ErrorCode::kInvalidArgument, "EM alignment: " + what); };
  if (!(sigma_m > 0) || !std::isfinite(sigma_m)) return bad("sigma_m must be > 0 metres (range noise along the line of sight)");
  if (sample_offsets_sigma.empty()) return bad("sample_offsets_sigma is empty (e.g. -3 -2 -1 0 1 2 3)");
  for (std::size_t j = 0; j < sample_offsets_sigma.size(); ++j) {
    if (!std::isfinite(sample_offsets_sigma[j])) return bad("sample offsets must be finite");
    if (j > 0 && !(sample_offsets_sigma[j] > sample_offsets_sigma[j - 1]))
      return bad("sample offsets must be strictly increasing");
  }
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (!(convergence_translation_m >= 0) || !(convergence_rotation_rad >= 0))
    return bad("convergence thresholds must be >= 0");
  if (subsample < 1) return bad("subsample must be >= 1 (every k-th vertex)");
  if (!(max_correspondence_m >= 0) || !std::isfinite(max_correspondence_m))
    return bad("max_correspondence_m must be >= 0 metres (0 = no limit)");
  if (!(outlier_mad_factor >= 0) || !(outlier_floor_sigma >= 0)) return bad("outlier factors must be >= 0 (0 = off)");
  if (min_correspondences < 6) return bad("min_correspondences must be >= 6");
  if (!(mesh_break_sigma >= 0) || !std::isfinite(mesh_break_sigma)) return bad("mesh_break_sigma must be >= 0");
  if (normal_window < 1) return bad("normal_window must be >= 1 cell");
  if (Status s = mesh.Validate(); !s) return s;
  return Status::Ok();
}

std::vector<double> EmSampleWeights(const std::vector<double>& t, double sigma) {
  const std::size_t m = t.size();
  std::vector<double> w(m, 0.0);
  const double k = 1.0 / (2.0 * std::sqrt(2.0) * sigma);
  for (std::size_t j = 0; j < m; ++j) {
    const double hi = j + 1 < m ? std::erf((t[j] + t[j + 1]) * k) : 1.0;
    const double lo = j > 0 ? std::erf((t[j] + t[j - 1]) * k) : -1.0;
    w[j] = 0.5 * (hi - lo);
  }
  return w;
}

RangeImageOptions EmMeshOptions(const EmOptions& options) {
  RangeImageOptions mesh = options.mesh;
  mesh.min_edge_break_m = std::max(mesh.min_edge_break_m, options.mesh_break_sigma * options.sigma_m);
  return mesh;
}

Expected<EmResult> AlignEm(const Scan& parent, const Scan& child, Eigen::Isometry3d initial_parent_from_child,
                           const EmOptions& options, ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const RangeImageOptions mesh = EmMeshOptions(options);
  Expected<RangeImageProjection> pp = RangeImageProjection::Create(parent, mesh);
  if (!pp) return pp.error();
  Expected<RangeImageProjection> cp = RangeImageProjection::Create(child, mesh);
  if (!cp) return cp.error();
  return AlignEm(*pp, *cp, initial_parent_from_child, options, progress, cancel);
}

Expected<EmResult> AlignEm(const RangeImageProjection& parent, const RangeImageProjection& child,
                           Eigen::Isometry3d pose, const EmOptions& options, ProgressSink& progress,
                           const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const Scan& cs = child.scan();
  const Scan& ps = parent.scan();
  const bool em = options.method == EmOptions::Method::kEm;
  const bool plane = options.method == EmOptions::Method::kPointToPlane ||
                     (em && options.residual == EmOptions::Residual::kPointToPlane);

  // Sample offsets (metres) and their weights.
  std::vector<double> offsets{0.0}, weights{1.0};
  if (em) {
    offsets.clear();
    for (double t : options.sample_offsets_sigma) offsets.push_back(t * options.sigma_m);
    weights = EmSampleWeights(offsets, options.sigma_m);
  }
  const int m = static_cast<int>(offsets.size());
  int central = 0;
  for (int j = 1; j < m; ++j)
    if (std::abs(offsets[j]) < std::abs(offsets[central])) central = j;

  // Child vertices and their lines of sight.
  std::vector<Eigen::Vector3d> x, v;
  for (std::size_t i = 0, k = 0; i < cs.size(); ++i) {
    if (!cs.valid[i]) continue;
    if (k++ % options.subsample) continue;
    x.push_back(cs.points[i].cast<double>());
    v.push_back(child.LineOfSight(x.back()));
  }
  const int n = static_cast<int>(x.size());

  // Parent normals for point-to-plane.
  std::vector<Eigen::Vector3f> normals;
  if (plane) {
    const double break_m = EmMeshOptions(options).min_edge_break_m;
    normals.assign(ps.size(), Eigen::Vector3f::Zero());
#pragma omp parallel for schedule(dynamic, 16)
    for (int r = 0; r < ps.rows; ++r)
      for (int c = 0; c < ps.cols; ++c)
        if (ps.IsValid(r, c)) normals[ps.Index(r, c)] = WindowNormal(ps, r, c, options.normal_window, break_m).cast<float>();
  }

  EmResult result;
  result.vertices = n;
  result.parent_camera = parent.fit();
  result.child_camera = child.fit();
  std::vector<Pair> pairs(static_cast<std::size_t>(n) * m);
  std::vector<Eigen::Vector3d> pair_normal(plane ? pairs.size() : 0);
  const double max_d = options.max_correspondence_m > 0 ? options.max_correspondence_m : std::numeric_limits<double>::infinity();

  for (int it = 0; it < options.max_iterations; ++it) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "EM alignment of '" + cs.name + "' to '" + ps.name + "' cancelled");
    progress.Report(double(it) / options.max_iterations, "EM alignment");
    // E-step: each sample's correspondence on the parent's line of sight through it.
    int hit_vertices = 0;
#pragma omp parallel for schedule(static) reduction(+ : hit_vertices)
    for (int i = 0; i < n; ++i) {
      bool any = false;
      for (int j = 0; j < m; ++j) {
        Pair& p = pairs[static_cast<std::size_t>(i) * m + j];
        p.ok = false;
        p.s = x[i] + offsets[j] * v[i];
        p.x = x[i];
        const Eigen::Vector3d sp = pose * p.s;
        double row = 0, col = 0;
        if (!parent.Project(sp, &row, &col) || !parent.SurfaceAlongLineOfSight(sp, &p.y)) continue;
        if ((p.y - sp).norm() > max_d) continue;
        if (plane) {
          const Eigen::Vector3f nf = normals[ps.Index(std::min(ps.rows - 1, int(std::lround(row))),
                                                      int(std::lround(col)) % ps.cols)];
          if (nf.squaredNorm() == 0) continue;
          pair_normal[static_cast<std::size_t>(i) * m + j] = nf.cast<double>();
        }
        p.w = weights[j];
        p.ok = true;
        any = true;
      }
      hit_vertices += any;
    }
    if (options.outlier_mad_factor > 0) {
      // Distance of each vertex's central pair (the sample nearest t = 0).
      std::vector<double> d0(n, -1.0), found;
      for (int i = 0; i < n; ++i) {
        const Pair& p = pairs[static_cast<std::size_t>(i) * m + central];
        if (p.ok) found.push_back(d0[i] = (p.y - pose * p.s).norm());
      }
      if (!found.empty()) {
        std::nth_element(found.begin(), found.begin() + found.size() / 2, found.end());
        const double thr = std::max(options.outlier_mad_factor * 1.4826 * found[found.size() / 2],
                                    options.outlier_floor_sigma * options.sigma_m);
        for (int i = 0; i < n; ++i)
          if (d0[i] < 0 || d0[i] > thr)
            for (int j = 0; j < m; ++j) pairs[static_cast<std::size_t>(i) * m + j].ok = false;
      }
    }
    std::vector<Eigen::Vector3d> src, dst, nrm, vtx;
    std::vector<double> w;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (!pairs[k].ok) continue;
      src.push_back(pairs[k].s);
      vtx.push_back(pairs[k].x);
      dst.push_back(pairs[k].y);
      w.push_back(pairs[k].w);
      if (plane) nrm.push_back(pair_normal[k]);
    }
    result.correspondences = static_cast<int>(src.size());
    result.overlap = n ? double(hit_vertices) / n : 0.0;
    if (result.correspondences < options.min_correspondences) {
      if (it == 0)
        return MakeError(ErrorCode::kFailed, "EM alignment: '" + cs.name + "' and '" + ps.name + "' do not overlap at the initial pose (" +
                                                 std::to_string(result.correspondences) +
                                                 " correspondences); start nearer or lower min_correspondences");
      break;
    }
    // M-step.
    Eigen::Isometry3d next = pose;
    if (plane) {
      Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
      for (std::size_t k = 0; k < src.size(); ++k) {
        const Eigen::Vector3d p = pose * vtx[k];
        Eigen::Matrix<double, 6, 1> jac;
        jac << p.cross(nrm[k]), nrm[k];
        const double r = (p - dst[k]).dot(nrm[k]);
        a += w[k] * jac * jac.transpose();
        b -= w[k] * r * jac;
      }
      const Eigen::Matrix<double, 6, 1> dx = a.ldlt().solve(b);
      if (!dx.allFinite()) break;
      next = SmallMotion(dx) * pose;
    } else {
      Expected<Eigen::Isometry3d> fit = FitRigid(src, dst, w);
      if (!fit) break;
      next = *fit;
    }
    const Eigen::Isometry3d delta = next * pose.inverse();
    pose = next;
    result.iterations = it + 1;
    // RMS at the updated pose over the E-step's pairs.
    double sum = 0, wsum = 0;
    for (std::size_t k = 0; k < src.size(); ++k) {
      sum += w[k] * (plane ? std::pow((pose * vtx[k] - dst[k]).dot(nrm[k]), 2) : (pose * src[k] - dst[k]).squaredNorm());
      wsum += w[k];
    }
    result.rms_m = wsum > 0 ? std::sqrt(sum / wsum) : 0.0;
    if (delta.translation().norm() < options.convergence_translation_m &&
        Eigen::AngleAxisd(delta.linear()).angle() < options.convergence_rotation_rad) {
      result.converged = true;
      break;
    }
  }
  result.parent_from_child = pose;
  progress.Report(1.0, "EM alignment");
  return result;
}

}  // namespace scanreg
