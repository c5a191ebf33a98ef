// Closed-form rigid fit between paired 3D points (Horn 1987/1988, Umeyama 1991), as used by
// W §4.3 to recover the pose from corresponding points in both frames.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "core/common/expected.h"

namespace scanreg {

// Weighted least-squares rotation + translation (no scale) minimising
// sum_i w_i |target_i - (R source_i + t)|^2; the SVD's reflection case is fixed (det = +1).
// Returns target_from_source. weights: empty (all 1) or one non-negative value per pair; pairs
// of weight 0 are ignored. Errors: sizes disagree, fewer than 3 pairs of positive weight, or a
// degenerate (collinear or coincident) source or target configuration.
Expected<Eigen::Isometry3d> FitRigid(const std::vector<Eigen::Vector3d>& source,
                                     const std::vector<Eigen::Vector3d>& target,
                                     const std::vector<double>& weights = {});

// Levelled frames (z up in both): the heading about z and the translation minimising the same sum,
// from 2 or more pairs (the yaw from the centred horizontal coordinates, the translation from the
// centroids). None with fewer than 2 pairs or horizontally coincident points.
std::optional<Eigen::Isometry3d> FitHeading(const std::vector<Eigen::Vector3d>& source,
                                            const std::vector<Eigen::Vector3d>& target,
                                            const std::vector<double>& weights = {});

}  // namespace scanreg
