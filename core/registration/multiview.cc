#include "core/registration/multiview.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace scanreg {
namespace {

// A residual of child sample `c` of view j against view i's sample `q`: r = m . (a - b) in the world,
// a = T_j p, b = T_i q, m = R_i n.
struct Match {
  Eigen::Vector3d a, m;
  double r = 0;
};

// Where sample p (normal n, both in i's frame) meets i's surface: among its 4 nearest samples of i
// within cutoff_m, the nearest whose normal is within 30° of n and that lies within tangent_m along
// its tangent plane. Returns that sample's index and the point-to-plane distance in *r; -1 when
// none (beyond i's border, across a corner, or a turned surface).
int Meet(const ViewSurface& vi, const Eigen::Vector3d& p, const Eigen::Vector3d& n, double cutoff_m, double tangent_m,
         double* r) {
  if (n.isZero()) return -1;
  for (int q : vi.index->KNearest(p, 4)) {
    const Eigen::Vector3d d = p - vi.points[q];
    if (d.squaredNorm() > cutoff_m * cutoff_m) break;
    const Eigen::Vector3d& m = vi.normals[q];
    if (m.isZero() || std::abs(m.dot(n)) < 0.866) continue;
    const double along = m.dot(d);
    if (d.squaredNorm() - along * along > tangent_m * tangent_m) continue;
    *r = along;
    return q;
  }
  return -1;
}

// Evenly strided indices of at most max_count of n.
std::vector<int> Strided(std::size_t n, int max_count) {
  std::vector<int> out;
  const double step = std::max(1.0, double(n) / std::max(1, max_count));
  for (double k = 0; k < n; k += step) out.push_back(static_cast<int>(k));
  return out;
}

// Matches of j's samples (strided) on i's surface at the given poses within cutoff.
std::vector<Match> PairMatches(const ViewSurface& vi, const ViewSurface& vj, const Eigen::Isometry3d& wi,
                               const Eigen::Isometry3d& wj, const std::vector<int>& samples, double cutoff_m) {
  std::vector<Match> out;
  const Eigen::Isometry3d i_from_j = wi.inverse() * wj;
  for (int s : samples) {
    const Eigen::Vector3d p = i_from_j * vj.points[s];
    double r = 0;
    const int q = Meet(vi, p, i_from_j.linear() * vj.normals[s], cutoff_m, cutoff_m, &r);
    if (q < 0) continue;
    Match mt;
    mt.a = wi * p;
    mt.m = wi.linear() * vi.normals[q];
    mt.r = r;
    out.push_back(mt);
  }
  return out;
}

Eigen::Isometry3d Exp(const Eigen::Matrix<double, 6, 1>& xi) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double angle = xi.head<3>().norm();
  if (angle > 0) t.linear() = Eigen::AngleAxisd(angle, xi.head<3>() / angle).toRotationMatrix();
  t.translation() = xi.tail<3>();
  return t;
}

}  // namespace

ViewSurface MakeViewSurface(std::vector<Eigen::Vector3d> samples, int k) {
  ViewSurface v;
  v.points = std::move(samples);
  v.index = std::make_unique<PointIndex>(v.points);
  v.normals.assign(v.points.size(), Eigen::Vector3d::Zero());
#pragma omp parallel for schedule(static)
  for (long s = 0; s < static_cast<long>(v.points.size()); ++s) {
    const std::vector<int> nn = v.index->KNearest(v.points[s], k);
    if (nn.size() < 5) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int q : nn) mean += v.points[q];
    mean /= nn.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int q : nn) cov += (v.points[q] - mean) * (v.points[q] - mean).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector3d ev = es.eigenvalues();  // ascending
    if (!(ev(1) > 0) || ev(0) > 0.1 * ev(1)) continue;  // no plane: a corner, an edge, clutter
    v.normals[s] = es.eigenvectors().col(0);
  }
  return v;
}

std::vector<std::pair<int, int>> OverlappingPairs(const std::vector<const ViewSurface*>& views,
                                                  const std::vector<Poses>& pose_sets, const std::vector<bool>& used,
                                                  double distance_m, double min_overlap) {
  const int n = static_cast<int>(views.size());
  std::vector<std::pair<int, int>> candidates, out;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (used[i] && used[j]) candidates.emplace_back(i, j);
  std::vector<char> keep(candidates.size(), 0);
#pragma omp parallel for schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(candidates.size()); ++k) {
    const auto [i, j] = candidates[k];
    for (const Poses& w : pose_sets) {
      const Eigen::Isometry3d i_from_j = w[i].inverse() * w[j];
      const double o = std::max(SampleOverlap(*views[i]->index, views[j]->points, i_from_j, distance_m),
                                SampleOverlap(*views[j]->index, views[i]->points, i_from_j.inverse(), distance_m));
      if (o >= min_overlap) keep[k] = 1;
      if (keep[k]) break;
    }
  }
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (keep[k]) out.push_back(candidates[k]);
  return out;
}

std::vector<Consistency> MeasureConsistency(const std::vector<const ViewSurface*>& views,
                                            const std::vector<Poses>& pose_sets,
                                            const std::vector<std::pair<int, int>>& pairs, double cutoff_m,
                                            double scale_m) {
  const int n = static_cast<int>(views.size());
  const int sets = static_cast<int>(pose_sets.size());
  const double s2 = scale_m * scale_m;
  // Per directed pair and pose set: the summed loss over the samples met at any set, and the squared
  // residuals of the samples met at that set.
  struct Sum {
    std::vector<double> loss, sq;
    std::vector<long> met;
    long count = 0;
  };
  std::vector<Sum> sums(2 * pairs.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (long k = 0; k < static_cast<long>(2 * pairs.size()); ++k) {
    const auto [a, b] = pairs[k / 2];
    const int i = k % 2 ? b : a, j = k % 2 ? a : b;  // j's samples on i's surface
    const ViewSurface& vi = *views[i];
    const ViewSurface& vj = *views[j];
    std::vector<Eigen::Isometry3d> i_from_j(sets);
    for (int s = 0; s < sets; ++s) i_from_j[s] = pose_sets[s][i].inverse() * pose_sets[s][j];
    Sum sum;
    sum.loss.assign(sets, 0.0);
    sum.sq.assign(sets, 0.0);
    sum.met.assign(sets, 0);
    std::vector<double> r(sets);
    std::vector<char> hit(sets);
    for (int idx : Strided(vj.points.size(), 4000)) {
      if (vj.normals[idx].isZero()) continue;
      bool any = false;
      for (int s = 0; s < sets; ++s) {
        const Eigen::Vector3d p = i_from_j[s] * vj.points[idx];
        hit[s] = Meet(vi, p, i_from_j[s].linear() * vj.normals[idx], cutoff_m, cutoff_m, &r[s]) >= 0;
        any |= hit[s] != 0;
      }
      if (!any) continue;
      for (int s = 0; s < sets; ++s) {
        if (!hit[s]) {
          sum.loss[s] += 1.0;  // met at another pose set, not at this one: the bounded loss's ceiling
          continue;
        }
        const double r2 = r[s] * r[s];
        sum.loss[s] += r2 / (r2 + s2);
        sum.sq[s] += r2;
        ++sum.met[s];
      }
      ++sum.count;
    }
    sums[k] = std::move(sum);
  }
  // Mean Geman-McClure loss m -> the RMS of residuals that would all give it: s sqrt(m / (1 - m)).
  auto robust_rms = [&](double loss, long count) {
    if (count <= 0) return 0.0;
    const double m = loss / count;
    return m >= 1.0 ? cutoff_m : std::min(cutoff_m, scale_m * std::sqrt(m / (1.0 - m)));
  };
  std::vector<Consistency> out(sets);
  for (int s = 0; s < sets; ++s) {
    Consistency& c = out[s];
    std::vector<double> scan_loss(n, 0.0);
    c.scan_samples.assign(n, 0);
    c.scan_rms_m.assign(n, 0.0);
    c.pair_rms_m.assign(pairs.size(), -1.0);
    double total = 0;
    for (std::size_t p = 0; p < pairs.size(); ++p) {
      long met = 0;
      double sq = 0;
      for (std::size_t k : {2 * p, 2 * p + 1}) {
        if (sums[k].count == 0) continue;
        total += sums[k].loss[s];
        c.samples += sums[k].count;
        for (int v : {pairs[p].first, pairs[p].second}) {
          scan_loss[v] += sums[k].loss[s];
          c.scan_samples[v] += sums[k].count;
        }
        met += sums[k].met[s];
        sq += sums[k].sq[s];
      }
      if (met > 0) c.pair_rms_m[p] = std::sqrt(sq / met);
    }
    c.rms_m = robust_rms(total, c.samples);
    for (int v = 0; v < n; ++v) c.scan_rms_m[v] = robust_rms(scan_loss[v], c.scan_samples[v]);
  }
  return out;
}

Expected<MultiViewResult> AlignMultiView(const std::vector<const ViewSurface*>& views, const Poses& start,
                                         const std::vector<std::pair<int, int>>& pairs, const std::vector<bool>& fixed,
                                         const MultiViewOptions& options, const CancelToken& cancel) {
  const int n = static_cast<int>(views.size());
  if (static_cast<int>(start.size()) != n || static_cast<int>(fixed.size()) != n)
    return MakeError(ErrorCode::kInvalidArgument, "multi-view step: one pose and one fixed flag per view");
  if (std::find(fixed.begin(), fixed.end(), true) == fixed.end())
    return MakeError(ErrorCode::kInvalidArgument, "multi-view step: at least one view must be fixed (the datum)");
  if (!(options.cutoff_m > 0)) return MakeError(ErrorCode::kInvalidArgument, "multi-view step: the cutoff must be > 0");
  MultiViewResult result;
  result.world = start;
  // Unknowns: 6 per free view, a left perturbation about the centre c of the scene (conditioning).
  std::vector<int> column(n, -1);
  int unknowns = 0;
  for (int v = 0; v < n; ++v)
    if (!fixed[v]) column[v] = 6 * (unknowns++);
  result.conditioning.assign(n, 0.0);
  if (unknowns == 0 || pairs.empty()) {
    result.converged = true;
    return result;
  }
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int v = 0; v < n; ++v) centre += start[v].translation();
  centre /= n;
  std::vector<std::vector<int>> samples(2 * pairs.size());
  for (std::size_t k = 0; k < 2 * pairs.size(); ++k) {
    const int j = k % 2 ? pairs[k / 2].first : pairs[k / 2].second;
    samples[k] = Strided(views[j]->points.size(), options.samples_per_pair);
  }
  const double floor_m = std::min(options.cutoff_m, std::max(options.floor_m, 0.0));
  for (int round = 0; round < options.rounds; ++round) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "registration cancelled");
    // The cutoff: the full reach for the first third of the rounds, then half, then a quarter.
    const double cutoff = std::max(floor_m, options.cutoff_m / (round < options.rounds / 3 ? 1 : round < 2 * options.rounds / 3 ? 2 : 4));
    const double kernel = 0.5 * cutoff;  // Cauchy scale
    std::vector<std::vector<Match>> matches(2 * pairs.size());
#pragma omp parallel for schedule(dynamic, 1)
    for (long k = 0; k < static_cast<long>(2 * pairs.size()); ++k) {
      const int i = k % 2 ? pairs[k / 2].second : pairs[k / 2].first;
      const int j = k % 2 ? pairs[k / 2].first : pairs[k / 2].second;
      matches[k] = PairMatches(*views[i], *views[j], result.world[i], result.world[j], samples[k], cutoff);
    }
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(6 * unknowns, 6 * unknowns);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(6 * unknowns);
    for (std::size_t k = 0; k < matches.size(); ++k) {
      const int i = k % 2 ? pairs[k / 2].second : pairs[k / 2].first;
      const int j = k % 2 ? pairs[k / 2].first : pairs[k / 2].second;
      const int ci = column[i], cj = column[j];
      if (ci < 0 && cj < 0) continue;
      Eigen::Matrix<double, 6, 6> hjj = Eigen::Matrix<double, 6, 6>::Zero();
      Eigen::Matrix<double, 6, 1> gj = Eigen::Matrix<double, 6, 1>::Zero();
      for (const Match& mt : matches[k]) {
        Eigen::Matrix<double, 6, 1> J;  // d r / d xi_j; d r / d xi_i = -J
        J.head<3>() = (mt.a - centre).cross(mt.m);
        J.tail<3>() = mt.m;
        const double w = 1.0 / (1.0 + (mt.r / kernel) * (mt.r / kernel));
        hjj += w * J * J.transpose();
        gj += w * mt.r * J;
      }
      if (cj >= 0) {
        H.block<6, 6>(cj, cj) += hjj;
        g.segment<6>(cj) += gj;
      }
      if (ci >= 0) {
        H.block<6, 6>(ci, ci) += hjj;
        g.segment<6>(ci) -= gj;
      }
      if (ci >= 0 && cj >= 0) {
        H.block<6, 6>(ci, cj) -= hjj;
        H.block<6, 6>(cj, ci) -= hjj;
      }
    }
    // A view no match reaches keeps its pose (a small damping keeps the system solvable).
    const double damping = 1e-9 * std::max(1.0, H.diagonal().maxCoeff());
    H.diagonal().array() += damping;
    const Eigen::VectorXd step = H.ldlt().solve(-g);
    if (!step.allFinite()) break;
    double moved = 0;
    for (int v = 0; v < n; ++v) {
      if (column[v] < 0) continue;
      const Eigen::Matrix<double, 6, 1> xi = step.segment<6>(column[v]);
      Eigen::Isometry3d about_centre = Eigen::Translation3d(centre) * Exp(xi) * Eigen::Translation3d(-centre);
      // How far the view's samples move: rotation times their distance from the centre plus the shift.
      const double reach = (result.world[v].translation() - centre).norm();
      moved = std::max(moved, xi.head<3>().norm() * (reach + cutoff) + xi.tail<3>().norm());
      result.world[v] = about_centre * result.world[v];
    }
    result.rounds = round + 1;
    if (moved < options.converged_m && round >= 2 * options.rounds / 3) {
      result.converged = true;
      break;
    }
  }
  // Conditioning of each free view at the final poses: its own information, rotation about its
  // samples' centre scaled by their spread so both halves are in metres.
  for (int v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& p : views[v]->points) c += p;
    c = result.world[v] * (c / std::max<std::size_t>(1, views[v]->points.size()));
    double spread = 0;
    for (int s : Strided(views[v]->points.size(), 2000)) spread += (result.world[v] * views[v]->points[s] - c).squaredNorm();
    spread = std::sqrt(spread / std::max<std::size_t>(1, Strided(views[v]->points.size(), 2000).size()));
    Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
    for (std::size_t k = 0; k < 2 * pairs.size(); ++k) {
      const int i = k % 2 ? pairs[k / 2].second : pairs[k / 2].first;
      const int j = k % 2 ? pairs[k / 2].first : pairs[k / 2].second;
      if (i != v && j != v) continue;
      for (const Match& mt :
           PairMatches(*views[i], *views[j], result.world[i], result.world[j], samples[k], std::max(floor_m, options.cutoff_m / 4))) {
        Eigen::Matrix<double, 6, 1> J;
        J.head<3>() = (mt.a - c).cross(mt.m) / std::max(spread, 1e-12);
        J.tail<3>() = mt.m;
        info += J * J.transpose();
      }
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(info);
    const double top = es.eigenvalues()(5);
    result.conditioning[v] = top > 0 ? std::max(0.0, es.eigenvalues()(0)) / top : 0.0;
  }
  return result;
}

}  // namespace scanreg
