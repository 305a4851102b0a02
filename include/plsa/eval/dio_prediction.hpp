// k-step-ahead and free-simulation outputs of any DIO model from its predicted
// increments dyhat (method notes): yhat(t) = y(t-k) + sum_{m=t-k+1..t} dyhat(m),
// and simulation yhat(t) = y(0) + sum_{m=1..t} dyhat(m). Shared by every tool.
#pragma once

#include <limits>
#include <string>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/eval/fit.hpp"

namespace plsa::eval {

/// A predicted trajectory aligned with the measurement: samples [first, T).
struct AlignedPrediction {
  Eigen::Index first = 0;
  Eigen::VectorXd values;  ///< values(i) predicts y(first + i)
};

/// The prediction over all `rows` samples of its log, NaN where it has none.
inline Eigen::VectorXd placedOver(const AlignedPrediction& p, Eigen::Index rows) {
  PLSA_CHECK(p.first >= 0 && p.first + p.values.size() <= rows,
             "placedOver: the prediction runs past the log's " + std::to_string(rows) + " rows");
  Eigen::VectorXd v = Eigen::VectorXd::Constant(rows, std::numeric_limits<double>::quiet_NaN());
  v.segment(p.first, p.values.size()) = p.values;
  return v;
}

/// k-step-ahead predictions, k >= 1, for every t >= k. dyhat(m) is the
/// model's increment for sample m (it may use inputs up to m, never y after m-1).
inline AlignedPrediction kStepAhead(const Eigen::Ref<const Eigen::VectorXd>& y,
                                    const Eigen::Ref<const Eigen::VectorXd>& dyhat, int k) {
  PLSA_CHECK(k >= 1, "kStepAhead: the horizon must be at least 1 step");
  PLSA_CHECK(y.size() == dyhat.size(), "kStepAhead: y and dyhat lengths differ");
  PLSA_CHECK(y.size() > k, "kStepAhead: the log (" + std::to_string(y.size()) +
                               " samples) is not longer than the horizon (" + std::to_string(k) + ")");
  const Eigen::Index T = y.size();
  AlignedPrediction out;
  out.first = k;
  out.values.resize(T - k);
  // Running window sum of the last k increments.
  double window = dyhat.segment(1, k).sum();
  for (Eigen::Index t = k; t < T; ++t) {
    if (t > k) window += dyhat(t) - dyhat(t - k);
    out.values(t - k) = y(t - k) + window;
  }
  return out;
}

/// Free simulation from the first measured sample.
inline AlignedPrediction simulate(const Eigen::Ref<const Eigen::VectorXd>& y,
                                  const Eigen::Ref<const Eigen::VectorXd>& dyhat) {
  PLSA_CHECK(y.size() == dyhat.size(), "simulate: y and dyhat lengths differ");
  PLSA_CHECK(y.size() >= 2, "simulate: need at least two samples");
  AlignedPrediction out;
  out.first = 1;
  out.values.resize(y.size() - 1);
  double acc = y(0);
  for (Eigen::Index t = 1; t < y.size(); ++t) {
    acc += dyhat(t);
    out.values(t - 1) = acc;
  }
  return out;
}

/// NRMSE fit of an aligned prediction against the measurement it predicts.
inline double fitOf(const Eigen::Ref<const Eigen::VectorXd>& y, const AlignedPrediction& p) {
  return nrmseFit(y.segment(p.first, p.values.size()), p.values);
}

/// Root-mean-square error of an aligned prediction, in the output's units.
inline double rmsErrorOf(const Eigen::Ref<const Eigen::VectorXd>& y, const AlignedPrediction& p) {
  return rmsError(y.segment(p.first, p.values.size()), p.values);
}

}  // namespace plsa::eval
