// Global registration: a pose graph over every accepted pairwise link (tree links and loop
// closures), solved with Ceres (Levenberg-Marquardt) under a robust kernel so one bad link cannot
// drag the network; the root scan is held fixed. Reports each link's residual before and after
// and which links the kernel down-weighted. Built only when Ceres is found (SCANREG_HAVE_POSE_GRAPH
// is then defined for users of scanreg::registration).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "core/common/expected.h"
#include "core/common/progress.h"

namespace scanreg {

struct PoseGraphLink {
  int parent = 0;  // indices into the pose list
  int child = 0;
  Eigen::Isometry3d parent_from_child = Eigen::Isometry3d::Identity();  // the pairwise result
};

struct PoseGraphOptions {
  enum class Kernel { kNone, kHuber, kCauchy };
  Kernel kernel = Kernel::kCauchy;
  // Link uncertainty: residuals are divided by these before the kernel (metres, radians).
  double translation_sigma_m = 0.005;
  double rotation_sigma_rad = 0.002;
  // Kernel scale on the normalised residual (in sigmas): beyond it a link counts less.
  double kernel_scale = 3.0;
  int root = 0;  // held fixed
  int max_iterations = 100;
  // A link is reported down-weighted when the kernel's weight at the solution is below this.
  double down_weight_threshold = 0.5;

  Status Validate() const;
};

struct PoseGraphLinkReport {
  int parent = 0, child = 0;
  double translation_before_m = 0, rotation_before_rad = 0;  // |link^-1 * (parent^-1 child)| at the initial poses
  double translation_after_m = 0, rotation_after_rad = 0;    // same at the solution
  double weight = 1.0;                                       // kernel weight at the solution, (0, 1]
  bool down_weighted = false;
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> world_from_scan;
  std::vector<PoseGraphLinkReport> links;
  int iterations = 0;
  double initial_cost = 0, final_cost = 0;
  bool converged = false;
};

// Errors: invalid options, a link naming a missing pose or itself, poses not connected to the
// root by links (kInvalidArgument), cancel (kCancelled, checked per solver iteration).
Expected<PoseGraphResult> OptimizePoseGraph(const std::vector<Eigen::Isometry3d>& initial_world_from_scan,
                                            const std::vector<PoseGraphLink>& links, const PoseGraphOptions& options,
                                            ProgressSink& progress, const CancelToken& cancel);

}  // namespace scanreg
