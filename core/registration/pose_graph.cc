#include "core/registration/pose_graph.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>

#include <cmath>
#include <string>

#include "core/registration/link_residual.h"

namespace scanreg {
namespace {

class CancelCallback : public ceres::IterationCallback {
 public:
  CancelCallback(const CancelToken& cancel, ProgressSink& progress, int max)
      : cancel_(cancel), progress_(progress), max_(max) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    progress_.Report(std::min(1.0, double(s.iteration) / max_), "pose graph");
    return cancel_.IsCancelled() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  const CancelToken& cancel_;
  ProgressSink& progress_;
  int max_;
};

void LinkError(const Eigen::Isometry3d& measured, const Eigen::Isometry3d& wp, const Eigen::Isometry3d& wc, double* t,
               double* r) {
  const Eigen::Isometry3d e = measured.inverse() * (wp.inverse() * wc);
  *t = e.translation().norm();
  *r = Eigen::AngleAxisd(e.linear()).angle();
}

}  // namespace

Status PoseGraphOptions::Validate() const {
  auto bad = [](const std::string& w) { return MakeError(ErrorCode::kInvalidArgument, "pose graph: " + w); };
  if (!(translation_sigma_m > 0) || !(rotation_sigma_rad > 0)) return bad("link sigmas must be > 0");
  if (!(kernel_scale > 0)) return bad("kernel_scale must be > 0 (sigmas)");
  if (max_iterations < 1) return bad("max_iterations must be >= 1");
  if (root < 0) return bad("root must be a pose index");
  if (!(down_weight_threshold > 0 && down_weight_threshold <= 1)) return bad("down_weight_threshold must be in (0, 1]");
  return Status::Ok();
}

Expected<PoseGraphResult> OptimizePoseGraph(const std::vector<Eigen::Isometry3d>& initial,
                                            const std::vector<PoseGraphLink>& links, const PoseGraphOptions& options,
                                            ProgressSink& progress, const CancelToken& cancel) {
  if (Status s = options.Validate(); !s) return s.error();
  const int n = static_cast<int>(initial.size());
  if (options.root >= n) return MakeError(ErrorCode::kInvalidArgument, "pose graph: root index beyond the poses");
  // Connectivity to the root (union-find).
  std::vector<int> up(n);
  for (int i = 0; i < n; ++i) up[i] = i;
  auto find = [&](int i) {
    while (up[i] != i) i = up[i] = up[up[i]];
    return i;
  };
  for (const PoseGraphLink& l : links) {
    if (l.parent < 0 || l.parent >= n || l.child < 0 || l.child >= n || l.parent == l.child)
      return MakeError(ErrorCode::kInvalidArgument, "pose graph: link " + std::to_string(l.parent) + " -> " +
                                                        std::to_string(l.child) + " names a missing pose or itself");
    up[find(l.parent)] = find(l.child);
  }
  for (int i = 0; i < n; ++i)
    if (find(i) != find(options.root))
      return MakeError(ErrorCode::kInvalidArgument, "pose graph: scan " + std::to_string(i) +
                                                        " has no link to the root; register it first or drop it");

  std::vector<Eigen::Quaterniond> q(n);
  std::vector<Eigen::Vector3d> t(n);
  for (int i = 0; i < n; ++i) {
    q[i] = Eigen::Quaterniond(initial[i].linear()).normalized();
    t[i] = initial[i].translation();
  }
  ceres::Problem problem;
  for (const PoseGraphLink& l : links) {
    auto* cost = new ceres::AutoDiffCostFunction<LinkResidual, 6, 4, 3, 4, 3>(
        new LinkResidual(l.parent_from_child, options.translation_sigma_m, options.rotation_sigma_rad));
    ceres::LossFunction* loss = nullptr;
    if (options.kernel == PoseGraphOptions::Kernel::kCauchy) loss = new ceres::CauchyLoss(options.kernel_scale);
    if (options.kernel == PoseGraphOptions::Kernel::kHuber) loss = new ceres::HuberLoss(options.kernel_scale);
    problem.AddResidualBlock(cost, loss, q[l.parent].coeffs().data(), t[l.parent].data(), q[l.child].coeffs().data(),
                             t[l.child].data());
  }
  for (int i = 0; i < n; ++i) {
    if (!problem.HasParameterBlock(q[i].coeffs().data())) continue;
    problem.SetManifold(q[i].coeffs().data(), new ceres::EigenQuaternionManifold);
  }
  if (problem.HasParameterBlock(t[options.root].data())) {
    problem.SetParameterBlockConstant(q[options.root].coeffs().data());
    problem.SetParameterBlockConstant(t[options.root].data());
  }
  PoseGraphResult result;
  result.links.reserve(links.size());
  for (const PoseGraphLink& l : links) {
    PoseGraphLinkReport r;
    r.parent = l.parent;
    r.child = l.child;
    LinkError(l.parent_from_child, initial[l.parent], initial[l.child], &r.translation_before_m, &r.rotation_before_rad);
    result.links.push_back(r);
  }
  if (!links.empty()) {
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    so.max_num_iterations = options.max_iterations;
    so.num_threads = 1;
    CancelCallback callback(cancel, progress, options.max_iterations);
    so.callbacks.push_back(&callback);
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    if (summary.termination_type == ceres::USER_FAILURE || cancel.IsCancelled())
      return MakeError(ErrorCode::kCancelled, "pose graph optimisation cancelled");
    result.iterations = static_cast<int>(summary.iterations.size());
    result.initial_cost = summary.initial_cost;
    result.final_cost = summary.final_cost;
    result.converged = summary.termination_type == ceres::CONVERGENCE;
  } else {
    result.converged = true;
  }
  result.world_from_scan.resize(n);
  for (int i = 0; i < n; ++i) {
    result.world_from_scan[i] = Eigen::Isometry3d::Identity();
    result.world_from_scan[i].linear() = q[i].normalized().toRotationMatrix();
    result.world_from_scan[i].translation() = t[i];
  }
  for (std::size_t k = 0; k < links.size(); ++k) {
    PoseGraphLinkReport& r = result.links[k];
    const PoseGraphLink& l = links[k];
    LinkError(l.parent_from_child, result.world_from_scan[l.parent], result.world_from_scan[l.child], &r.translation_after_m,
              &r.rotation_after_rad);
    // Kernel weight rho'(s) at the solution, s = squared normalised residual.
    LinkResidual cost(l.parent_from_child, options.translation_sigma_m, options.rotation_sigma_rad);
    double res[6];
    cost(q[l.parent].coeffs().data(), t[l.parent].data(), q[l.child].coeffs().data(), t[l.child].data(), res);
    double s = 0;
    for (double v : res) s += v * v;
    double rho[3] = {s, 1.0, 0.0};
    if (options.kernel == PoseGraphOptions::Kernel::kCauchy) ceres::CauchyLoss(options.kernel_scale).Evaluate(s, rho);
    if (options.kernel == PoseGraphOptions::Kernel::kHuber) ceres::HuberLoss(options.kernel_scale).Evaluate(s, rho);
    r.weight = rho[1];
    r.down_weighted = r.weight < options.down_weight_threshold;
  }
  progress.Report(1.0, "pose graph");
  return result;
}

}  // namespace scanreg
