// The NRMSE fit used throughout: fit = 100 (1 - ||y - yhat|| / ||y - mean y||),
// 100 is perfect, 0 is no better than the mean, negative is worse; and the
// same error in the output's own units.
#pragma once

#include <cmath>
#include <string>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"

namespace plsa::eval {

namespace detail {
// What every error measure needs of a measured and a predicted signal.
inline void requireComparable(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& yhat,
                              const char* who, Eigen::Index min_samples) {
  const std::string w = who;
  PLSA_CHECK(y.size() == yhat.size(), w + ": measured and predicted lengths differ (" + std::to_string(y.size()) +
                                          " vs " + std::to_string(yhat.size()) + ")");
  PLSA_CHECK(y.size() >= min_samples, w + ": need at least " + std::to_string(min_samples) + " sample(s)");
  PLSA_CHECK(y.allFinite(), w + ": the measured signal contains NaN or Inf");
  PLSA_CHECK(yhat.allFinite(), w + ": the predicted signal contains NaN or Inf");
}
}  // namespace detail

/// Throws if the sizes differ, the signal is constant, or a value is not finite.
inline double nrmseFit(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& yhat) {
  detail::requireComparable(y, yhat, "nrmseFit", 2);
  const double spread = (y.array() - y.mean()).matrix().norm();
  PLSA_CHECK(spread > 0.0, "nrmseFit: the measured signal is constant, the fit is undefined");
  return 100.0 * (1.0 - (y - yhat).norm() / spread);
}

/// sqrt(mean (y - yhat)^2), in the output's units: a fit says how much of a
/// run's spread a model misses, this how far off it is, and a run that
/// hardly moves can make the two read very differently.
inline double rmsError(const Eigen::Ref<const Eigen::VectorXd>& y, const Eigen::Ref<const Eigen::VectorXd>& yhat) {
  detail::requireComparable(y, yhat, "rmsError", 1);
  return (y - yhat).norm() / std::sqrt(static_cast<double>(y.size()));
}

/// Standard deviation of the measured signal: what rmsError is read against
/// (fit = 100 (1 - rms / spread)).
inline double spreadOf(const Eigen::Ref<const Eigen::VectorXd>& y) {
  PLSA_CHECK(y.size() >= 1 && y.allFinite(), "spreadOf: need finite samples");
  return (y.array() - y.mean()).matrix().norm() / std::sqrt(static_cast<double>(y.size()));
}

}  // namespace plsa::eval
