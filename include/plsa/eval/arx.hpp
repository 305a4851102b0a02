// Linear ARX baseline, one MISO model per output on levels (not differences):
//   y_k = sum_{i=1..na} a_i y_{k-i} + sum_j sum_{i=1..nb} b_{j,i} u_{j,k-i} + c,
// with k-step-ahead prediction (measured y up to t-k, inputs known) and simulation.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/eval/dio_prediction.hpp"

namespace plsa::eval {

struct ArxModel {
  int na = 4;
  int nb = 4;
  Eigen::MatrixXd theta;  ///< (na + n_u nb + 1) x n_y

  /// Least squares over several records. Throws on mismatched records.
  static ArxModel fit(const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& Y, int na, int nb,
                      double ridge = 1e-9);
  /// k-step-ahead predictions of output `o` for samples t >= max(na, nb) - 1 + k.
  AlignedPrediction kStepAhead(const Eigen::MatrixXd& u, const Eigen::VectorXd& y, int o, int k) const;
  /// Free simulation of output `o`, started from the first max(na, nb) measured samples.
  AlignedPrediction simulate(const Eigen::MatrixXd& u, const Eigen::VectorXd& y, int o) const;
};

}  // namespace plsa::eval
