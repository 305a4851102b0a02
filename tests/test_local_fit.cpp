// Step 2: a local LTI fit of one step, and the segments it refuses (plsa/identify/local_fit.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "plsa/identify/local_fit.hpp"

using namespace plsa::identify;

TEST(LocalFit, RecoversFirstOrderPoleAndRejectsBadSegments) {
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.02);
  const double a = 0.95, b = 0.5;
  Eigen::VectorXd u = Eigen::VectorXd::Constant(300, 1.0), y(300);
  double prev = 0.0;
  for (int k = 0; k < 300; ++k) {
    y(k) = a * prev + b * (k == 0 ? 0.0 : 1.0);
    prev = y(k);
  }
  // y(k) responds to u from k-1; the segment starts at the step.
  Eigen::VectorXd yk(300);
  prev = 0.0;
  for (int k = 0; k < 300; ++k) {
    yk(k) = a * prev + b * 1.0;
    prev = yk(k);
  }
  for (int k = 0; k < 300; ++k) yk(k) += noise(rng);
  const LocalFit f = fitLocalModel(u, yk, 0.0, 0.0);
  ASSERT_TRUE(f.usable) << f.reason;
  EXPECT_NEAR(f.poles[0].real(), a, 0.01);
  EXPECT_NEAR(f.gain, b / (1 - a), 0.5);
  // Pure noise: badly determined or too small, never passed on.
  Eigen::VectorXd n(300);
  for (int k = 0; k < 300; ++k) n(k) = noise(rng);
  const LocalFit bad = fitLocalModel(u, n, 0.0, 0.0);
  EXPECT_FALSE(bad.usable);
  EXPECT_FALSE(bad.reason.empty());
  // A diverging response: unstable pole reported.
  Eigen::VectorXd g(300);
  for (int k = 0; k < 300; ++k) g(k) = std::pow(1.01, k) - 1.0;
  const LocalFit unstable = fitLocalModel(u, g, 0.0, 0.0);
  EXPECT_FALSE(unstable.usable);
  EXPECT_NE(unstable.reason.find("unstable"), std::string::npos) << unstable.reason;
}
