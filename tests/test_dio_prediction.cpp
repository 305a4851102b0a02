// k-step-ahead prediction and simulation of a DIO model from its increments (plsa/eval/dio_prediction.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "plsa/dio/dio_transform.hpp"
#include "plsa/eval/dio_prediction.hpp"

TEST(DioPrediction, KStepAheadMatchesDirectSum) {
  std::mt19937 rng(9);
  std::normal_distribution<double> n01;
  const int T = 300;
  Eigen::VectorXd y(T), dyhat(T);
  for (int t = 0; t < T; ++t) {
    y(t) = n01(rng);
    dyhat(t) = n01(rng);
  }
  for (int k : {1, 7, 40}) {
    const auto p = plsa::eval::kStepAhead(y, dyhat, k);
    ASSERT_EQ(p.first, k);
    ASSERT_EQ(p.values.size(), T - k);
    for (int t = k; t < T; ++t) {
      double want = y(t - k);
      for (int m = t - k + 1; m <= t; ++m) want += dyhat(m);
      EXPECT_NEAR(p.values(t - k), want, 1e-11) << "k=" << k << " t=" << t;
    }
  }
}

TEST(DioPrediction, PerfectIncrementsGivePerfectFits) {
  const int T = 200;
  Eigen::VectorXd y(T);
  for (int t = 0; t < T; ++t) y(t) = std::sin(0.05 * t) + 0.1 * t;
  Eigen::VectorXd dy = plsa::dioDifference(y);
  EXPECT_NEAR(plsa::eval::fitOf(y, plsa::eval::simulate(y, dy)), 100.0, 1e-9);
  EXPECT_NEAR(plsa::eval::fitOf(y, plsa::eval::kStepAhead(y, dy, 40)), 100.0, 1e-9);
  // A biased model drifts in simulation but is reset in k-step prediction.
  dy.array() += 0.01;
  EXPECT_GT(plsa::eval::fitOf(y, plsa::eval::kStepAhead(y, dy, 1)), plsa::eval::fitOf(y, plsa::eval::simulate(y, dy)));
}

TEST(DioPrediction, RejectsHorizonLongerThanLog) {
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(10, 0, 1);
  EXPECT_THROW(plsa::eval::kStepAhead(y, y, 10), std::invalid_argument);
  EXPECT_THROW(plsa::eval::kStepAhead(y, y, 0), std::invalid_argument);
}
