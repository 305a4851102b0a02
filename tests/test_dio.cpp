#include <gtest/gtest.h>

#include <random>

#include "plsa/dio/dio_transform.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/eval/fit.hpp"

TEST(Dio, DifferenceFollowsPaperEquation8AndIntegrates) {
  Eigen::MatrixXd x(4, 2);
  x << 1, 5, 3, 5, 2, 7, 2, 8;
  const Eigen::MatrixXd d = plsa::dioDifference(x);
  Eigen::MatrixXd want(4, 2);
  want << 1, 5, 2, 0, -1, 2, 0, 1;
  EXPECT_EQ(d, want);
  EXPECT_EQ(plsa::dioIntegrate(d), x);
}

TEST(Dio, AtRestStartsWithZeroDifference) {
  Eigen::MatrixXd x(3, 1);
  x << 4, 6, 5;
  const Eigen::MatrixXd d = plsa::dioDifference(x, plsa::DioStart::kAtRest);
  EXPECT_EQ(d(0, 0), 0.0);
  EXPECT_EQ(d(1, 0), 2.0);
  EXPECT_EQ(plsa::dioIntegrate(d, x.row(0)), x);
}

TEST(Dio, RandomRoundTrip) {
  std::mt19937 rng(2);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd x(200, 3);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = n01(rng);
  EXPECT_LT((plsa::dioIntegrate(plsa::dioDifference(x)) - x).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Fit, NrmseDefinition) {
  Eigen::VectorXd y(4), yhat(4);
  y << 0, 1, 2, 3;
  yhat << 0, 1, 2, 3;
  EXPECT_DOUBLE_EQ(plsa::nrmseFit(y, yhat), 100.0);
  yhat.setConstant(1.5);  // the mean: fit 0
  EXPECT_NEAR(plsa::nrmseFit(y, yhat), 0.0, 1e-12);
  yhat << 1, 1, 2, 3;  // ||e|| = 1, ||y - mean|| = sqrt(5)
  EXPECT_NEAR(plsa::nrmseFit(y, yhat), 100.0 * (1.0 - 1.0 / std::sqrt(5.0)), 1e-12);
}

TEST(Fit, RmsErrorIsInTheOutputsUnitsAndReadsAgainstTheSpread) {
  Eigen::VectorXd y(4), yhat(4);
  y << 0, 1, 2, 3;
  yhat << 1, 1, 2, 3;  // one sample off by 1: rms 1/2
  EXPECT_NEAR(plsa::rmsError(y, yhat), 0.5, 1e-15);
  EXPECT_NEAR(plsa::spreadOf(y), std::sqrt(5.0 / 4.0), 1e-15);
  // fit = 100 (1 - rms / spread), whatever the scale of the output.
  for (double scale : {1e-3, 1.0, 250.0}) {
    const Eigen::VectorXd ys = scale * y, yhats = scale * yhat;
    EXPECT_NEAR(plsa::rmsError(ys, yhats), 0.5 * scale, 1e-12 * scale);
    EXPECT_NEAR(plsa::nrmseFit(ys, yhats), 100.0 * (1.0 - plsa::rmsError(ys, yhats) / plsa::spreadOf(ys)), 1e-9);
  }
  // A constant signal has no fit but does have an error.
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(4, 2.0);
  EXPECT_NEAR(plsa::rmsError(flat, flat.array() + 0.25), 0.25, 1e-15);
  Eigen::VectorXd n = yhat;
  n(2) = std::nan("");
  EXPECT_THROW(plsa::rmsError(y, n), std::invalid_argument);
  EXPECT_THROW(plsa::rmsError(y, Eigen::VectorXd(3)), std::invalid_argument);
}

TEST(Fit, RejectsBadInput) {
  Eigen::VectorXd y = Eigen::VectorXd::Constant(5, 2.0);
  EXPECT_THROW(plsa::nrmseFit(y, y), std::invalid_argument);
  Eigen::VectorXd a(3), b(4);
  a << 1, 2, 3;
  b << 1, 2, 3, 4;
  EXPECT_THROW(plsa::nrmseFit(a, b), std::invalid_argument);
  Eigen::VectorXd n = a;
  n(1) = std::nan("");
  EXPECT_THROW(plsa::nrmseFit(a, n), std::invalid_argument);
}

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
    const auto p = plsa::kStepAhead(y, dyhat, k);
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
  EXPECT_NEAR(plsa::fitOf(y, plsa::simulate(y, dy)), 100.0, 1e-9);
  EXPECT_NEAR(plsa::fitOf(y, plsa::kStepAhead(y, dy, 40)), 100.0, 1e-9);
  // A biased model drifts in simulation but is reset in k-step prediction.
  dy.array() += 0.01;
  EXPECT_GT(plsa::fitOf(y, plsa::kStepAhead(y, dy, 1)), plsa::fitOf(y, plsa::simulate(y, dy)));
}

TEST(DioPrediction, RejectsHorizonLongerThanLog) {
  Eigen::VectorXd y = Eigen::VectorXd::LinSpaced(10, 0, 1);
  EXPECT_THROW(plsa::kStepAhead(y, y, 10), std::invalid_argument);
  EXPECT_THROW(plsa::kStepAhead(y, y, 0), std::invalid_argument);
}
