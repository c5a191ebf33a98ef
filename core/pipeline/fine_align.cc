#include "core/pipeline/fine_align.h"

#include <algorithm>

#include "core/pipeline/register_pair.h"
#include "core/registration/icp.h"
#include "core/registration/voxel_filter.h"

namespace scanreg::pipeline {

EmOptions PipelineEmOptions(const RegisterOptions& options, const Scan& child) {
  EmOptions o;
  o.method = options.fine == FineMethod::kProjectiveIcp ? EmOptions::Method::kProjectiveIcp : EmOptions::Method::kEm;
  // The noise model is at least a twentieth of the reach: with a measured noise far below the start
  // error (the bunny: 0.06 mm against 1.7 cm) the posterior collapses onto the nearest samples and
  // the iteration walks off (measured: 5 deg / 5 mm starts ended 36 deg off; with this, 0.5 mm as the
  // README's flags give).
  o.sigma_m = std::max({options.range_sigma_m, options.overlap_distance_m / 20.0, 1e-6});
  o.max_correspondence_m = options.overlap_distance_m;
  o.outlier_mad_factor = 3.0;  // occlusions (measured on the Stanford bunny: bench_em.cc)
  o.subsample = std::max<int>(1, static_cast<int>(child.CountValid() / 10000));
  o.max_iterations = 100;
  o.convergence_translation_m = 1e-3 * o.sigma_m;
  return o;
}

Expected<FineResult> AlignFine(const PreparedScan& parent, const PreparedScan& child, const Eigen::Isometry3d& initial,
                               const RegisterOptions& options, const CancelToken& cancel) {
  NullProgress quiet;
  FineResult out;
  switch (options.fine) {
    case FineMethod::kKeypoints:
      return MakeError(ErrorCode::kInvalidArgument,
                       "fine method 'keypoints' needs feature matches; use em, projective-icp or dense");
    case FineMethod::kDense: {
      const std::shared_ptr<const IcpSurface> surface = parent.Surface();
      Expected<IcpResult> icp =
          surface ? DenseIcpSurface(*surface, ThinEvenly(child.samples, options.dense_icp.max_samples), initial,
                                    options.dense_icp, quiet, cancel)  // thinned as it would: only those widened
                  : DenseIcpSamples(ToDouble(parent.samples), ToDouble(child.samples), initial, options.dense_icp,
                                    quiet, cancel);
      if (!icp) return icp.error();
      out.parent_from_child = icp->parent_from_child;
      out.iterations = icp->iterations;
      out.converged = icp->converged;
      return out;
    }
    case FineMethod::kEm:
    case FineMethod::kProjectiveIcp: {
      const Expected<std::shared_ptr<const Scan>> p = parent.Full(), c = child.Full();
      if (!p || !c) return (p ? c : p).error();
      const EmOptions em = PipelineEmOptions(options, **c);
      Expected<EmResult> r = AlignEm(**p, **c, initial, em, quiet, cancel);
      if (!r)
        return MakeError(r.error().code, EmMethodName(em) + " of '" + child.name + "' to '" + parent.name +
                                             "': " + r.error().message);
      out.parent_from_child = r->parent_from_child;
      out.iterations = r->iterations;
      out.converged = r->converged;
      return out;
    }
  }
  return MakeError(ErrorCode::kInvalidArgument, "unknown fine method");
}

}  // namespace scanreg::pipeline
