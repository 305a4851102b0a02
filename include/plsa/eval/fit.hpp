// The NRMSE fit used throughout: fit = 100 (1 - ||y - yhat|| / ||y - mean y||),
// 100 is perfect, 0 is no better than the mean, negative is worse.
#pragma once

#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"

namespace plsa {

/// Throws if the sizes differ, the signal is constant, or a value is not finite.
inline double nrmseFit(const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& yhat) {
  require(y.size() == yhat.size(), "nrmseFit: measured and predicted lengths differ (" +
                                       std::to_string(y.size()) + " vs " +
                                       std::to_string(yhat.size()) + ")");
  require(y.size() >= 2, "nrmseFit: need at least two samples");
  require(y.allFinite(), "nrmseFit: the measured signal contains NaN or Inf");
  require(yhat.allFinite(), "nrmseFit: the predicted signal contains NaN or Inf");
  const double spread = (y.array() - y.mean()).matrix().norm();
  require(spread > 0.0, "nrmseFit: the measured signal is constant, the fit is undefined");
  return 100.0 * (1.0 - (y - yhat).norm() / spread);
}

}  // namespace plsa
