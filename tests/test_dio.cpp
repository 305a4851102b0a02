// The DIO transforms: differences and their integration (plsa/dio/dio_transform.hpp).
#include <gtest/gtest.h>

#include <random>

#include "plsa/dio/dio_transform.hpp"

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
