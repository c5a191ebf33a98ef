#include "core/registration/surface_distance.h"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "core/registration/point_index.h"

namespace scanreg {

std::vector<double> PointToSurfaceDistances(const PointIndex& index, const std::vector<Eigen::Vector3d>& surface,
                                            const std::vector<Eigen::Vector3d>& queries, double max_distance_m) {
  std::vector<double> distances(queries.size(), -1.0);
  if (surface.size() < 3) return distances;
#pragma omp parallel for schedule(static)
  for (long i = 0; i < static_cast<long>(queries.size()); ++i) {
    const Eigen::Vector3d& q = queries[i];
    if (index.Nearest(q, max_distance_m) < 0) continue;
    const std::vector<int> nn = index.KNearest(q, 8);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (int k : nn) mean += surface[k];
    mean /= double(nn.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (int k : nn) cov += (surface[k] - mean) * (surface[k] - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const double d = std::abs((q - mean).dot(eig.eigenvectors().col(0)));
    if (d <= max_distance_m) distances[i] = d;
  }
  return distances;
}

}  // namespace scanreg
