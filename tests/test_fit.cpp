// The NRMSE fit and the RMS error in the output's units (plsa/eval/fit.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "plsa/eval/fit.hpp"

TEST(Fit, NrmseDefinition) {
  Eigen::VectorXd y(4), yhat(4);
  y << 0, 1, 2, 3;
  yhat << 0, 1, 2, 3;
  EXPECT_DOUBLE_EQ(plsa::eval::nrmseFit(y, yhat), 100.0);
  yhat.setConstant(1.5);  // the mean: fit 0
  EXPECT_NEAR(plsa::eval::nrmseFit(y, yhat), 0.0, 1e-12);
  yhat << 1, 1, 2, 3;  // ||e|| = 1, ||y - mean|| = sqrt(5)
  EXPECT_NEAR(plsa::eval::nrmseFit(y, yhat), 100.0 * (1.0 - 1.0 / std::sqrt(5.0)), 1e-12);
}

TEST(Fit, RmsErrorIsInTheOutputsUnitsAndReadsAgainstTheSpread) {
  Eigen::VectorXd y(4), yhat(4);
  y << 0, 1, 2, 3;
  yhat << 1, 1, 2, 3;  // one sample off by 1: rms 1/2
  EXPECT_NEAR(plsa::eval::rmsError(y, yhat), 0.5, 1e-15);
  EXPECT_NEAR(plsa::eval::spreadOf(y), std::sqrt(5.0 / 4.0), 1e-15);
  // fit = 100 (1 - rms / spread), whatever the scale of the output.
  for (double scale : {1e-3, 1.0, 250.0}) {
    const Eigen::VectorXd ys = scale * y, yhats = scale * yhat;
    EXPECT_NEAR(plsa::eval::rmsError(ys, yhats), 0.5 * scale, 1e-12 * scale);
    EXPECT_NEAR(plsa::eval::nrmseFit(ys, yhats),
                100.0 * (1.0 - plsa::eval::rmsError(ys, yhats) / plsa::eval::spreadOf(ys)), 1e-9);
  }
  // A constant signal has no fit but does have an error.
  const Eigen::VectorXd flat = Eigen::VectorXd::Constant(4, 2.0);
  EXPECT_NEAR(plsa::eval::rmsError(flat, flat.array() + 0.25), 0.25, 1e-15);
  Eigen::VectorXd n = yhat;
  n(2) = std::nan("");
  EXPECT_THROW(plsa::eval::rmsError(y, n), std::invalid_argument);
  EXPECT_THROW(plsa::eval::rmsError(y, Eigen::VectorXd(3)), std::invalid_argument);
}

TEST(Fit, RejectsBadInput) {
  Eigen::VectorXd y = Eigen::VectorXd::Constant(5, 2.0);
  EXPECT_THROW(plsa::eval::nrmseFit(y, y), std::invalid_argument);
  Eigen::VectorXd a(3), b(4);
  a << 1, 2, 3;
  b << 1, 2, 3, 4;
  EXPECT_THROW(plsa::eval::nrmseFit(a, b), std::invalid_argument);
  Eigen::VectorXd n = a;
  n(1) = std::nan("");
  EXPECT_THROW(plsa::eval::nrmseFit(a, n), std::invalid_argument);
}
