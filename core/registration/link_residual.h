// The residual of one scan-to-scan link as a Ceres auto-diff functor (header only, Eigen): the
// measured parent_from_child against the poses' relative pose, as (2 vec(q_err) / sigma_r,
// t_err / sigma_t) with err = measured^-1 * (parent^-1 * child). Poses are (unit quaternion
// x, y, z, w as Eigen stores it, translation). Shared by the pose graph and the georeferencing
// adjustment.
#pragma once

#include <Eigen/Geometry>

namespace scanreg {

struct LinkResidual {
  LinkResidual(const Eigen::Isometry3d& measured, double sigma_t, double sigma_r)
      : q_inv(Eigen::Quaterniond(measured.linear()).conjugate()),
        t(measured.translation()),
        sigma_t(sigma_t),
        sigma_r(sigma_r) {}

  template <typename T>
  bool operator()(const T* qp_, const T* tp_, const T* qc_, const T* tc_, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qp(qp_), qc(qc_);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> tp(tp_), tc(tc_);
    const Eigen::Quaternion<T> qp_inv = qp.conjugate();
    const Eigen::Quaternion<T> q_rel = qp_inv * qc;
    const Eigen::Matrix<T, 3, 1> t_rel = qp_inv * (tc - tp);
    const Eigen::Quaternion<T> qmi = q_inv.cast<T>();
    const Eigen::Quaternion<T> q_err = qmi * q_rel;
    const Eigen::Matrix<T, 3, 1> t_err = qmi * (t_rel - t.cast<T>());
    const T sign = q_err.w() < T(0) ? T(-1) : T(1);
    for (int k = 0; k < 3; ++k) {
      r[k] = sign * T(2) * q_err.vec()[k] / T(sigma_r);
      r[3 + k] = t_err[k] / T(sigma_t);
    }
    return true;
  }

  Eigen::Quaterniond q_inv;
  Eigen::Vector3d t;
  double sigma_t, sigma_r;
};

}  // namespace scanreg
