// The predictor's two agreement checks, run along a log as a controller
// would call it: planned predictions against the offline predictions of the
// same model, and the held-input paths against a plan that repeats the input.
// Shared by the identified-model tests (test_predictor.cpp) and the typed
// suite over pole counts (test_predictor_hand_built.cpp).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include <Eigen/Dense>

#include "plsa/eval/validation.hpp"
#include "plsa/predict/predictor.hpp"

namespace plsa::test {

/// The largest difference seen, how far the predictions moved from the
/// measured output (a check that never moved shows nothing), and how many
/// calls were compared.
struct Agreement {
  double worst = 0.0, moved = 0.0;
  int compared = 0;
};

/// Feeds p the run (u, y) at sample time dt and, every `stride` samples,
/// predicts max(horizons) steps under the run's own next inputs, comparing
/// each horizon k with `offline[o].at(k)` (predictOutputs of the same model).
template <class P>
Agreement plannedAgainstOffline(P& p, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, double dt,
                                const std::vector<std::map<int, eval::AlignedPrediction>>& offline,
                                const std::vector<int>& horizons, int stride) {
  const int H = *std::max_element(horizons.begin(), horizons.end());
  Eigen::MatrixXd out(H, y.cols());
  Agreement a;
  for (Eigen::Index t = 0; t + H < u.rows(); ++t) {
    if (p.update(static_cast<double>(t) * dt, u.row(t), y.row(t)) != PredictorStatus::kOk) {
      ADD_FAILURE() << "update refused at t=" << t;
      return a;
    }
    if (t % stride != 0) continue;
    if (p.predict(H, u.middleRows(t + 1, H - 1), out) != PredictorStatus::kOk) {
      ADD_FAILURE() << "predict refused at t=" << t;
      return a;
    }
    for (Eigen::Index o = 0; o < y.cols(); ++o)
      for (int k : horizons) {
        const double v = out(k - 1, o);
        a.worst = std::max(a.worst, std::abs(v - offline[static_cast<std::size_t>(o)].at(k).values(t)));
        a.moved = std::max(a.moved, std::abs(v - y(t, o)));
      }
    ++a.compared;
  }
  return a;
}

/// Feeds p the run and, at every sample t with t % stride == offset, predicts
/// `horizon` steps with the input held (no plan: the closed-form paths) and
/// under a plan repeating u(t); `moved` is how far the held prediction travels.
template <class P>
Agreement heldAgainstRepeatedPlan(P& p, const Eigen::MatrixXd& u, const Eigen::MatrixXd& y, double dt, int horizon,
                                  int stride, int offset) {
  Eigen::MatrixXd held(horizon, y.cols()), repeated(horizon, y.cols());
  Agreement a;
  for (Eigen::Index t = 0; t < u.rows(); ++t) {
    if (p.update(static_cast<double>(t) * dt, u.row(t), y.row(t)) != PredictorStatus::kOk) {
      ADD_FAILURE() << "update refused at t=" << t;
      return a;
    }
    if (t % stride != offset) continue;
    if (p.predict(horizon, Eigen::MatrixXd(0, u.cols()), held) != PredictorStatus::kOk ||
        p.predict(horizon, u.row(t).replicate(horizon - 1, 1), repeated) != PredictorStatus::kOk) {
      ADD_FAILURE() << "predict refused at t=" << t;
      return a;
    }
    a.worst = std::max(a.worst, (held - repeated).cwiseAbs().maxCoeff());
    a.moved = std::max(a.moved, (held.row(horizon - 1) - held.row(0)).norm());
    ++a.compared;
  }
  return a;
}

}  // namespace plsa::test
