#include "core/georef/georeference.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "core/registration/link_residual.h"
#include "core/registration/rigid_fit.h"

namespace scanreg::georef {
namespace {

// A target seen by a scan: pose * centre - X, over sigma.
struct ObservationCost {
  ObservationCost(const Eigen::Vector3d& c, double sigma) : c(c), s(sigma) {}
  template <typename T>
  bool operator()(const T* q_, const T* t_, const T* x_, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t(t_), x(x_);
    const Eigen::Matrix<T, 3, 1> e = q * c.cast<T>() + t - x;
    for (int k = 0; k < 3; ++k) r[k] = e[k] / T(s);
    return true;
  }
  Eigen::Vector3d c;
  double s;
};

// A control coordinate (local frame): X - C, over sigma.
struct ControlCost {
  ControlCost(const Eigen::Vector3d& c, double sigma) : c(c), s(sigma) {}
  template <typename T>
  bool operator()(const T* x_, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = (x_[k] - T(c[k])) / T(s);
    return true;
  }
  Eigen::Vector3d c;
  double s;
};

// A levelled scan (tilt compensator, or the project setting): its vertical `u` (in its own frame:
// its z axis, or what the file's pose says) is the control frame's, within sigma (radians): the
// horizontal part of R u over sigma.
struct LevelCost {
  LevelCost(double sigma, const Eigen::Vector3d& up) : s(sigma), u(up.normalized()) {}
  template <typename T>
  bool operator()(const T* q_, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    const Eigen::Matrix<T, 3, 1> up = q * u.cast<T>();
    r[0] = up.x() / T(s);
    r[1] = up.y() / T(s);
    return true;
  }
  double s;
  Eigen::Vector3d u;
};

// A pull of a scan to where the registration put it (moved with the datum). Weak (metre / 0.1 rad)
// for every scan: keeps one that no link or target constrains where it was relative to the rest,
// negligible against links and targets. Stiff (0.1 mm / 1e-6 rad) for a held scan (a hand
// placement): it stays as placed.
struct PriorCost {
  PriorCost(const Eigen::Isometry3d& pose, double sigma_t, double sigma_r)
      : q_inv(Eigen::Quaterniond(pose.linear()).conjugate()), t(pose.translation()), st(sigma_t), sr(sigma_r) {}
  template <typename T>
  bool operator()(const T* q_, const T* t_, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> tt(t_);
    const Eigen::Quaternion<T> e = q_inv.cast<T>() * q;
    const T sign = e.w() < T(0) ? T(-1) : T(1);
    for (int k = 0; k < 3; ++k) {
      r[k] = sign * T(2) * e.vec()[k] / T(sr);
      r[3 + k] = (tt[k] - T(t[k])) / T(st);
    }
    return true;
  }
  Eigen::Quaterniond q_inv;
  Eigen::Vector3d t;
  double st, sr;
};

struct Target {
  std::string name;             // user-given name, or empty
  std::vector<int> obs;         // observation indices
  Eigen::Vector3d world = Eigen::Vector3d::Zero();  // mean position in the registration frame
  int control = -1;             // tied control point
};

// Observations grouped into targets: named ones by name, the others by proximity in the registration
// frame (single linkage within tol; each observation joins the nearest target).
std::vector<Target> GroupTargets(const std::vector<Eigen::Vector3d>& world, const std::vector<TargetObservation>& obs,
                                 double tol) {
  std::vector<Target> targets;
  std::map<std::string, int> by_name;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (obs[i].name.empty()) continue;
    auto [it, added] = by_name.emplace(obs[i].name, static_cast<int>(targets.size()));
    if (added) targets.push_back({obs[i].name, {}, {}, -1});
    targets[it->second].obs.push_back(static_cast<int>(i));
  }
  for (std::size_t i = 0; i < obs.size(); ++i) {
    if (!obs[i].name.empty()) continue;
    int best = -1;
    double best_d = tol;
    for (std::size_t t = 0; t < targets.size(); ++t) {
      for (int j : targets[t].obs) {
        const double d = (world[j] - world[i]).norm();
        if (d < best_d) best_d = d, best = static_cast<int>(t);
      }
    }
    if (best < 0) {
      best = static_cast<int>(targets.size());
      targets.push_back({});
    }
    targets[best].obs.push_back(static_cast<int>(i));
  }
  for (Target& t : targets) {
    for (int j : t.obs) t.world += world[j];
    t.world /= static_cast<double>(t.obs.size());
  }
  return targets;
}

// Ties unnamed targets to control points by the constellation: for triangles of targets and control
// points with matching sides, the rigid motion under which the most targets land within tol of a
// control point (ties broken by the smaller sum of distances). When another motion ties as many
// targets to other control points, the constellation is symmetric: nothing is tied and the reason
// is returned (the user names one target). up: the vertical in the registration frame.
std::string MatchConstellation(std::vector<Target>& targets, const std::vector<io::ControlPoint>& control,
                        const Eigen::Vector3d& origin, double tol, double max_tilt_rad, const Eigen::Vector3d& up) {
  std::vector<bool> taken(control.size(), false);
  for (const Target& t : targets)
    if (t.control >= 0) taken[t.control] = true;
  std::vector<int> free_t, free_c;
  for (std::size_t i = 0; i < targets.size(); ++i)
    if (targets[i].control < 0 && targets[i].name.empty()) free_t.push_back(static_cast<int>(i));
  for (std::size_t i = 0; i < control.size(); ++i)
    if (!taken[i]) free_c.push_back(static_cast<int>(i));
  if (free_t.empty() || free_c.empty()) return {};
  std::vector<Eigen::Vector3d> C(control.size());
  for (std::size_t i = 0; i < control.size(); ++i) C[i] = control[i].position - origin;
  auto assign = [&](const Eigen::Isometry3d& T, std::vector<int>* match, double* sum) {
    match->assign(targets.size(), -1);
    *sum = 0;
    int n = 0;
    std::vector<bool> used(control.size(), false);
    for (int t : free_t) {
      const Eigen::Vector3d p = T * targets[t].world;
      int best = -1;
      double best_d = tol;
      for (int c : free_c) {
        const double d = (C[c] - p).norm();
        if (!used[c] && d < best_d) best_d = d, best = c;
      }
      if (best >= 0) {
        used[best] = true;
        (*match)[t] = best;
        *sum += best_d;
        ++n;
      }
    }
    return n;
  };
  // Already-tied targets fix the motion when there are 3 of them.
  std::vector<Eigen::Vector3d> a, b;
  for (const Target& t : targets)
    if (t.control >= 0) a.push_back(t.world), b.push_back(C[t.control]);
  int best_n = 0;
  double best_sum = 0;
  std::vector<int> best_match;
  bool rival = false;  // another assignment ties as many targets
  auto consider = [&](const Eigen::Isometry3d& T) {
    // A motion that tips the vertical over is the constellation's mirror image, not the survey.
    if (std::acos(std::clamp((T.linear() * up).z(), -1.0, 1.0)) > max_tilt_rad) return;
    for (std::size_t i = 0; i < a.size(); ++i)  // targets the user named must land on their points
      if ((T * a[i] - b[i]).norm() > tol) return;
    std::vector<int> match;
    double sum = 0;
    const int n = assign(T, &match, &sum);
    if (n == 0 || n < best_n) return;
    if (n > best_n) {
      best_n = n, best_sum = sum, best_match = match, rival = false;
      return;
    }
    if (match != best_match) rival = true;
    if (sum < best_sum) best_sum = sum, best_match = match;
  };
  if (a.size() >= 3) {
    if (Expected<Eigen::Isometry3d> T = FitRigid(a, b)) consider(*T);
  } else {
    const int nt = std::min<int>(free_t.size(), 60), nc = std::min<int>(free_c.size(), 60);
    auto dist_t = [&](int i, int j) { return (targets[free_t[i]].world - targets[free_t[j]].world).norm(); };
    auto dist_c = [&](int i, int j) { return (C[free_c[i]] - C[free_c[j]]).norm(); };
    const double side_tol = 2 * tol;
    for (int i = 0; i < nc; ++i)
      for (int j = 0; j < nc; ++j) {
        if (j == i || dist_c(i, j) < 4 * tol) continue;
        for (int k = j + 1; k < nc; ++k) {
          if (k == i) continue;
          for (int ti = 0; ti < nt; ++ti)
            for (int tj = 0; tj < nt; ++tj) {
              if (tj == ti || std::abs(dist_t(ti, tj) - dist_c(i, j)) > side_tol) continue;
              for (int tk = 0; tk < nt; ++tk) {
                if (tk == ti || tk == tj || std::abs(dist_t(ti, tk) - dist_c(i, k)) > side_tol ||
                    std::abs(dist_t(tj, tk) - dist_c(j, k)) > side_tol)
                  continue;
                Expected<Eigen::Isometry3d> T =
                    FitRigid({targets[free_t[ti]].world, targets[free_t[tj]].world, targets[free_t[tk]].world},
                             {C[free_c[i]], C[free_c[j]], C[free_c[k]]});
                if (T) consider(*T);
              }
            }
        }
      }
  }
  if (best_n < 3 && a.size() + best_n < 3) return {};
  if (rival && best_n >= 3) {
    return "the targets match the control points in more than one way (a symmetric layout): name at least one "
           "target after its control point";
  }
  for (int t : free_t)
    if (!best_match.empty() && best_match[t] >= 0) targets[t].control = best_match[t];
  return {};
}

// The adjustment's inputs in the local frame (control minus origin) and its solution.
struct Adjustment {
  const std::vector<ScanLink>* links = nullptr;
  const std::vector<TargetObservation>* observations = nullptr;
  const std::vector<io::ControlPoint>* control = nullptr;
  const GeorefOptions* options = nullptr;
  std::vector<Eigen::Isometry3d> start;   // scan poses, local frame
  std::vector<bool> held;                 // scans kept as placed
  std::vector<Eigen::Vector3d> up_in_scan;  // levelled scans' verticals in their own frames (empty: z)
  std::vector<Eigen::Vector3d> start_x;   // target positions, local frame
  std::vector<int> target_of_obs;         // observation -> target
  std::vector<int> target_of_control;     // control point -> target (-1: none)
  std::vector<Eigen::Vector3d> control_local;

  struct Solution {
    std::vector<Eigen::Quaterniond> q;
    std::vector<Eigen::Vector3d> t, x;
  };

  // Least squares over links, observations and the control points `used`. False when Ceres fails.
  // cov_target >= 0: *cov receives that target's 3x3 position covariance (m^2) in the solution.
  bool Solve(const std::vector<int>& used, Solution* out, int cov_target = -1, Eigen::Matrix3d* cov = nullptr) const {
    const int n = static_cast<int>(start.size());
    Solution& s = *out;
    s.q.resize(n);
    s.t.resize(n);
    for (int i = 0; i < n; ++i) {
      s.q[i] = Eigen::Quaterniond(start[i].linear()).normalized();
      s.t[i] = start[i].translation();
    }
    s.x = start_x;
    const GeorefOptions& o = *options;
    ceres::Problem problem;
    for (int i = 0; i < n; ++i) {
      const bool stiff = i < static_cast<int>(held.size()) && held[i];
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PriorCost, 6, 4, 3>(
                                   new PriorCost(start[i], stiff ? 1e-4 : 1.0, stiff ? 1e-6 : 0.1)),
                               nullptr,
                               s.q[i].coeffs().data(), s.t[i].data());
      problem.SetManifold(s.q[i].coeffs().data(), new ceres::EigenQuaternionManifold);
      if (o.levelled_sigma_rad > 0) {
        const Eigen::Vector3d up = i < static_cast<int>(up_in_scan.size()) && up_in_scan[i].norm() > 0.5
                                       ? up_in_scan[i]
                                       : Eigen::Vector3d::UnitZ();
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<LevelCost, 2, 4>(new LevelCost(o.levelled_sigma_rad, up)), nullptr,
            s.q[i].coeffs().data());
      }
    }
    for (const ScanLink& l : *links) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<LinkResidual, 6, 4, 3, 4, 3>(new LinkResidual(
                                   l.parent_from_child, o.link_translation_sigma_m, o.link_rotation_sigma_rad)),
                               new ceres::CauchyLoss(3.0), s.q[l.parent].coeffs().data(), s.t[l.parent].data(),
                               s.q[l.child].coeffs().data(), s.t[l.child].data());
    }
    for (std::size_t j = 0; j < observations->size(); ++j) {
      const TargetObservation& ob = (*observations)[j];
      const double sigma = std::max(ob.sigma_m, o.min_observation_sigma_m);
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<ObservationCost, 3, 4, 3, 3>(new ObservationCost(ob.center, sigma)), nullptr,
          s.q[ob.scan].coeffs().data(), s.t[ob.scan].data(), s.x[target_of_obs[j]].data());
    }
    for (int k : used) {
      const double sigma = (*control)[k].sigma_m.value_or(o.default_control_sigma_m);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ControlCost, 3, 3>(new ControlCost(control_local[k], sigma)),
                               nullptr, s.x[target_of_control[k]].data());
    }
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.max_num_iterations = 100;
    so.num_threads = 1;
    so.function_tolerance = 1e-12;
    so.parameter_tolerance = 1e-12;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (summary.termination_type == ceres::FAILURE) return false;
    if (cov_target < 0) return true;
    ceres::Covariance::Options co;
    co.num_threads = 1;
    ceres::Covariance covariance(co);
    const double* x = s.x[cov_target].data();
    const std::vector<std::pair<const double*, const double*>> blocks{{x, x}};
    if (!covariance.Compute(blocks, &problem)) return false;
    double c[9];
    covariance.GetCovarianceBlock(x, x, c);
    *cov = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(c);
    return true;
  }

  // Control point k's residual (control minus adjusted target) in a solution.
  Eigen::Vector3d Residual(const Solution& s, int k) const { return control_local[k] - s.x[target_of_control[k]]; }
};

// The p-quantile of chi-square with 3 degrees of freedom (bisection on its distribution function
// erf(sqrt(x/2)) - sqrt(2x/pi) exp(-x/2)).
double ChiSquare3Quantile(double p) {
  double lo = 0, hi = 200;
  for (int i = 0; i < 100; ++i) {
    const double x = 0.5 * (lo + hi);
    const double cdf = std::erf(std::sqrt(x / 2)) - std::sqrt(2 * x / M_PI) * std::exp(-x / 2);
    (cdf < p ? lo : hi) = x;
  }
  return 0.5 * (lo + hi);
}

}  // namespace

const char* ControlRoleName(ControlRole role) {
  switch (role) {
    case ControlRole::kUsed: return "used";
    case ControlRole::kCheck: return "check";
    case ControlRole::kBlunder: return "blunder";
    case ControlRole::kNotFound: return "not found";
  }
  return "?";
}

Grade GradeOf(double residual_m, double tolerance_m) {
  if (residual_m > tolerance_m) return Grade::kRed;
  return residual_m < 0.5 * tolerance_m ? Grade::kGreen : Grade::kOrange;
}

const char* GradeName(Grade grade) {
  switch (grade) {
    case Grade::kGreen: return "green";
    case Grade::kOrange: return "orange";
    case Grade::kRed: return "red";
  }
  return "?";
}

Status GeorefOptions::Validate() const {
  auto bad = [](const std::string& w) { return MakeError(ErrorCode::kInvalidArgument, "georeferencing: " + w); };
  if (!(match_tolerance_m > 0 && match_tolerance_m <= 10)) return bad("the match tolerance must be in (0, 10] m");
  if (!(default_control_sigma_m > 0 && default_control_sigma_m <= 10)) return bad("the control sigma must be in (0, 10] m");
  if (!(min_observation_sigma_m > 0 && min_observation_sigma_m <= 1)) return bad("the target sigma must be in (0, 1] m");
  if (!(link_translation_sigma_m > 0) || !(link_rotation_sigma_rad > 0)) return bad("link sigmas must be > 0");
  if (!(tolerance_m > 0 && tolerance_m <= 10)) return bad("the control tolerance must be in (0, 10] m");
  if (!(levelled_sigma_rad >= 0 && levelled_sigma_rad <= 0.1))
    return bad("the levelling accuracy must be 0 (not levelled) or up to 0.1 rad (5.7 degrees)");
  if (!(max_tilt_deg > 0 && max_tilt_deg <= 180)) return bad("the maximum tilt must be in (0, 180] degrees");
  return Status::Ok();
}

Expected<GeorefResult> Georeference(const std::vector<Eigen::Isometry3d>& poses, const std::vector<ScanLink>& links,
                                    const std::vector<TargetObservation>& observations,
                                    const std::vector<io::ControlPoint>& control, const GeorefOptions& o,
                                    const CancelToken& cancel, const std::vector<bool>& held,
                                    const std::vector<Eigen::Vector3d>& up_in_scan) {
  if (Status s = o.Validate(); !s) return s.error();
  const int n_scans = static_cast<int>(poses.size());
  for (const TargetObservation& ob : observations)
    if (ob.scan < 0 || ob.scan >= n_scans || !ob.center.allFinite())
      return MakeError(ErrorCode::kInvalidArgument, "georeferencing: a target observation names no scan");
  for (const ScanLink& l : links)
    if (l.parent < 0 || l.parent >= n_scans || l.child < 0 || l.child >= n_scans || l.parent == l.child)
      return MakeError(ErrorCode::kInvalidArgument, "georeferencing: a link names no scan");
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const io::ControlPoint& c : control) origin += c.position;
  if (!control.empty()) origin /= static_cast<double>(control.size());
  origin = origin.array().round();  // a round local origin: printable, and exact in double

  // 1-2. Targets, tied to control by name or constellation.
  std::vector<Eigen::Vector3d> world(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) world[i] = poses[observations[i].scan] * observations[i].center;
  std::vector<Target> targets = GroupTargets(world, observations, o.match_tolerance_m);
  std::map<std::string, int> control_index;
  for (std::size_t i = 0; i < control.size(); ++i) control_index[control[i].name] = static_cast<int>(i);
  for (Target& t : targets) {
    auto it = control_index.find(t.name);
    if (!t.name.empty() && it != control_index.end()) t.control = it->second;
  }
  // The registration frame's vertical: the first scan's, as its file's pose gives it when it does.
  const Eigen::Vector3d registration_up =
      poses.empty() ? Eigen::Vector3d::UnitZ() : (poses[0].linear() * (!up_in_scan.empty() && up_in_scan[0].norm() > 0.5 ? up_in_scan[0].normalized()
                                                                                : Eigen::Vector3d::UnitZ()))
                                                         .normalized();
  const std::string ambiguity = MatchConstellation(targets, control, origin, o.match_tolerance_m,
                                                   o.max_tilt_deg * M_PI / 180.0, registration_up);

  // 3. Roles and blunders.
  GeorefResult result;
  result.targets = static_cast<int>(targets.size());
  result.control.resize(control.size());
  std::vector<int> target_of(control.size(), -1);
  for (std::size_t t = 0; t < targets.size(); ++t)
    if (targets[t].control >= 0) target_of[targets[t].control] = static_cast<int>(t);
  std::vector<Eigen::Vector3d> from(control.size(), Eigen::Vector3d::Zero()), to(control.size());
  std::vector<int> used;
  for (std::size_t i = 0; i < control.size(); ++i) {
    ControlResidual& r = result.control[i];
    r.name = control[i].name;
    to[i] = control[i].position - origin;
    if (target_of[i] < 0) {
      r.role = ControlRole::kNotFound;
      continue;
    }
    from[i] = targets[target_of[i]].world;
    r.observations = static_cast<int>(targets[target_of[i]].obs.size());
    r.role = control[i].check ? ControlRole::kCheck : ControlRole::kUsed;
    if (r.role == ControlRole::kUsed) used.push_back(static_cast<int>(i));
  }
  auto too_few = [&] {
    std::string found;
    for (const ControlResidual& r : result.control)
      if (r.role != ControlRole::kNotFound) found += (found.empty() ? "" : ", ") + r.name + " (" + ControlRoleName(r.role) + ")";
    return MakeError(ErrorCode::kFailed,
                     "georeferencing needs at least 3 control points seen in the scans; " + std::to_string(used.size()) +
                         " can place the project (" + std::to_string(targets.size()) + " targets found in the scans" +
                         (found.empty() ? "" : "; tied: " + found) + "). " +
                         (ambiguity.empty() ? "Check the control names, the target radius and that the targets are "
                                              "within the scans' range"
                                            : "Here " + ambiguity));
  };
  if (used.size() < 3) return too_few();
  std::vector<Eigen::Vector3d> a, b;
  for (int k : used) a.push_back(from[k]), b.push_back(to[k]);
  Expected<Eigen::Isometry3d> local_from_world = FitRigid(a, b);
  if (!local_from_world) {
    return MakeError(ErrorCode::kFailed,
                     "georeferencing: the control points tied to targets lie on one line; at least 3 not in line are needed");
  }

  // 4. The adjustment, in the local frame; blunders by leaving each used point out in turn.
  Adjustment adj;
  adj.links = &links;
  adj.observations = &observations;
  adj.control = &control;
  adj.options = &o;
  adj.control_local = to;
  adj.held = held;
  adj.up_in_scan = up_in_scan;
  adj.target_of_control = target_of;
  for (int i = 0; i < n_scans; ++i) adj.start.push_back(*local_from_world * poses[i]);
  for (const Target& t : targets) adj.start_x.push_back(*local_from_world * t.world);
  adj.target_of_obs.assign(observations.size(), -1);
  for (std::size_t k = 0; k < targets.size(); ++k)
    for (int j : targets[k].obs) adj.target_of_obs[j] = static_cast<int>(k);
  Adjustment::Solution solution;
  // Leave-one-out residual of control point k (metres) and its test statistic: the squared residual
  // over its expected covariance (the others' placement of the target plus the point's own sigma),
  // chi-square with 3 degrees of freedom for a point without blunder.
  auto leave_one_out = [&](int k, double* w) {
    std::vector<int> others;
    for (int i : used)
      if (i != k) others.push_back(i);
    Adjustment::Solution s;
    Eigen::Matrix3d cov;
    if (!adj.Solve(others, &s, target_of[k], &cov)) return -1.0;
    const double sigma = control[k].sigma_m.value_or(o.default_control_sigma_m);
    const Eigen::Vector3d r = adj.Residual(s, k);
    *w = r.dot((cov + sigma * sigma * Eigen::Matrix3d::Identity()).ldlt().solve(r));
    return r.norm();
  };
  // A blunder: the largest statistic beyond the chi-square(3) quantile at 1 - 0.001 / n (a 0.1 %
  // chance that any of the n points of a round without blunder is thrown out) whose residual also
  // exceeds the tolerance (a point within tolerance is never thrown out).
  while (o.detect_blunders && used.size() >= 4) {
    if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "georeferencing cancelled");
    int worst = -1;
    double worst_w = ChiSquare3Quantile(1.0 - 0.001 / used.size());
    for (int k : used) {
      double w = 0;
      const double r = leave_one_out(k, &w);
      result.control[k].leave_one_out_m = r;
      if (r > o.tolerance_m && w > worst_w) worst_w = w, worst = k;
    }
    if (worst < 0) break;
    result.control[worst].role = ControlRole::kBlunder;
    result.control[worst].leave_one_out_m = -1;
    used.erase(std::find(used.begin(), used.end(), worst));
    for (int k : used) result.control[k].leave_one_out_m = -1;  // measured with the blunder in
  }
  if (used.size() < 3) return too_few();
  if (!adj.Solve(used, &solution)) return MakeError(ErrorCode::kFailed, "georeferencing: the adjustment did not converge");
  if (cancel.IsCancelled()) return MakeError(ErrorCode::kCancelled, "georeferencing cancelled");

  result.world_from_scan.resize(n_scans);
  for (int i = 0; i < n_scans; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = solution.q[i].normalized().toRotationMatrix();
    pose.translation() = solution.t[i] + origin;
    result.world_from_scan[i] = pose;
  }
  result.observation_target.resize(observations.size());
  result.observation_residual_m.resize(observations.size());
  int unnamed = 0;
  std::vector<std::string> names(targets.size());
  for (std::size_t k = 0; k < targets.size(); ++k)
    names[k] = targets[k].control >= 0 ? control[targets[k].control].name
               : !targets[k].name.empty() ? targets[k].name
                                          : "t" + std::to_string(++unnamed);
  for (std::size_t j = 0; j < observations.size(); ++j) {
    const int k = adj.target_of_obs[j], s = observations[j].scan;
    result.observation_target[j] = names[k];
    const Eigen::Vector3d p = solution.q[s].normalized() * observations[j].center + solution.t[s];
    result.observation_residual_m[j] = (p - solution.x[k]).norm();
  }
  double sum = 0;
  for (std::size_t i = 0; i < control.size(); ++i) {
    ControlResidual& r = result.control[i];
    if (r.role == ControlRole::kNotFound) continue;
    r.delta = adj.Residual(solution, static_cast<int>(i));
    if (r.role == ControlRole::kUsed) sum += r.delta.squaredNorm();
  }
  result.used = static_cast<int>(used.size());
  result.rms_m = std::sqrt(sum / used.size());
  return result;
}

}  // namespace scanreg::georef

