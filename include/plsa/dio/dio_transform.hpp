// Difference-input-output (DIO) transforms, paper eq. (8)-(9): the model runs
// on du_k = u_k - u_{k-1} and dy_k = y_k - y_{k-1}; integration inverts it.
#pragma once

#include <Eigen/Dense>

namespace plsa {

/// What the first difference is taken against.
enum class DioStart {
  kFromZero,  ///< paper eq. (8): d_1 = x_1, as if the signal was 0 before the log
  kAtRest,    ///< d_1 = 0: the system was at rest at its first sample
};

/// Row-wise differences of a T x n signal (rows are samples).
inline Eigen::MatrixXd dioDifference(const Eigen::MatrixXd& x, DioStart start = DioStart::kFromZero) {
  Eigen::MatrixXd d(x.rows(), x.cols());
  if (x.rows() == 0) return d;
  d.row(0) = start == DioStart::kFromZero ? Eigen::RowVectorXd(x.row(0)) : Eigen::RowVectorXd::Zero(x.cols());
  for (Eigen::Index k = 1; k < x.rows(); ++k) d.row(k) = x.row(k) - x.row(k - 1);
  return d;
}

/// Inverse of dioDifference: x_k = x0 + sum_{m<=k} d_m, x0 the value before the log
/// (zero for kFromZero; the first sample for kAtRest).
inline Eigen::MatrixXd dioIntegrate(const Eigen::MatrixXd& d, const Eigen::RowVectorXd& x0) {
  Eigen::MatrixXd x(d.rows(), d.cols());
  Eigen::RowVectorXd acc = x0;
  for (Eigen::Index k = 0; k < d.rows(); ++k) {
    acc += d.row(k);
    x.row(k) = acc;
  }
  return x;
}

inline Eigen::MatrixXd dioIntegrate(const Eigen::MatrixXd& d) {
  return dioIntegrate(d, Eigen::RowVectorXd::Zero(d.cols()));
}

}  // namespace plsa
