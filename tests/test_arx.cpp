// The ARX baseline: a known ARX system recovered, predicted and simulated (plsa/eval/arx.hpp).
#include <gtest/gtest.h>

#include <random>

#include "plsa/eval/arx.hpp"

using namespace plsa;

TEST(Arx, RecoversAKnownArxSystem) {
  std::mt19937 rng(6);
  std::normal_distribution<double> n01;
  const int T = 3000;
  Eigen::MatrixXd u(T, 1), y(T, 1);
  u(0, 0) = y(0, 0) = y(1, 0) = 0;
  for (int k = 1; k < T; ++k) u(k, 0) = n01(rng);
  for (int k = 2; k < T; ++k) y(k, 0) = 1.5 * y(k - 1, 0) - 0.6 * y(k - 2, 0) + 0.3 * u(k - 1, 0) + 0.1;
  const eval::ArxModel m = eval::ArxModel::fit({u}, {y}, 2, 1, 0.0);
  EXPECT_NEAR(m.theta(0, 0), 1.5, 1e-6);
  EXPECT_NEAR(m.theta(1, 0), -0.6, 1e-6);
  EXPECT_NEAR(m.theta(2, 0), 0.3, 1e-6);
  EXPECT_NEAR(m.theta(3, 0), 0.1, 1e-6);
  EXPECT_NEAR(eval::fitOf(y.col(0), m.kStepAhead(u, y.col(0), 0, 20)), 100.0, 1e-6);
  EXPECT_NEAR(eval::fitOf(y.col(0), m.simulate(u, y.col(0), 0)), 100.0, 1e-6);
}
