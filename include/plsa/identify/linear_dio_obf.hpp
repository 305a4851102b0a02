// A single-region (global linear) DIO-OBF model, y_k = y_{k-1} + sum_j c_j^T
// [B_j(q) du_j]_k, fitted by ridge least squares. It is the DIO-PWL-OBF model
// with one region, and the "global linear OBF" baseline the PWL model must beat.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/core/pole_set.hpp"
#include "plsa/dio/dio_transform.hpp"

namespace plsa::identify {

/// OBF states of every input's bank, side by side: row t holds the states at
/// time t (driven by du up to t-1). Inputs are the T x n_u matrix u.
Eigen::MatrixXd dioObfRegressors(const std::vector<PoleSet>& poles_per_input, const Eigen::MatrixXd& u,
                                 DioStart start = DioStart::kAtRest);

struct LinearDioObf {
  std::vector<PoleSet> poles_per_input;
  Eigen::MatrixXd coefficients;  ///< regressors x outputs

  /// Ridge least squares on dy; throws on mismatched sizes or non-finite data.
  static LinearDioObf fit(const std::vector<PoleSet>& poles_per_input, const std::vector<Eigen::MatrixXd>& inputs,
                          const std::vector<Eigen::MatrixXd>& outputs, double ridge = 1e-6);
  /// Predicted increments dyhat (T x n_y) for an input record.
  Eigen::MatrixXd increments(const Eigen::MatrixXd& u) const;
};

}  // namespace plsa::identify
