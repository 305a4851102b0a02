// The NRMSE fit and the RMS error in the output's units (plsa/eval/fit.hpp);
// the paired gain of one model's scores over another's (paired_gain.hpp).
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <utility>
#include <vector>

#include "plsa/eval/fit.hpp"
#include "plsa/eval/paired_gain.hpp"

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

// The one-standard-error rule's numbers (plsa/eval/paired_gain.hpp).
TEST(PairedGain, MeanAndStandardErrorOfThePairedDifferences) {
  // Differences 1, 2, 3: mean 2, sample variance 1, error 1/sqrt(3).
  const auto [gain, se] = plsa::eval::pairedGain({91.0, 82.0, 73.0}, {90.0, 80.0, 70.0});
  EXPECT_NEAR(gain, 2.0, 1e-12);
  EXPECT_NEAR(se, 1.0 / std::sqrt(3.0), 1e-12);
  // A loss is a negative gain, with the same error.
  const auto [loss, se_loss] = plsa::eval::pairedGain({90.0, 80.0, 70.0}, {91.0, 82.0, 73.0});
  EXPECT_NEAR(loss, -2.0, 1e-12);
  EXPECT_NEAR(se_loss, se, 1e-12);
  // A term either side could not score is skipped with its pair, not
  // re-paired: the differences are still 1 and 3.
  const auto [g_nan, se_nan] = plsa::eval::pairedGain({91.0, NAN, 73.0}, {90.0, 80.0, 70.0});
  EXPECT_NEAR(g_nan, 2.0, 1e-12);
  EXPECT_NEAR(se_nan, 1.0, 1e-12);  // sd sqrt(2), over sqrt(2) pairs
}

// The slow poles' rule: three folds of two outputs, terms alternating by
// output (fold 0 out 0, fold 0 out 1, fold 1 out 0, ...). The held-out terms
// of the generalisation matrix's power-law creep (seed 2) when written:
// bending gained 10.1 +- 2.9, steering -4.2 +- 5.5, overall 2.9 +- 4.2.
TEST(PairedGain, ClearGainKeepsWhatOneOutputShowsPlainlyAndNoneLoses) {
  using plsa::eval::clearGain;
  const std::vector<double> base = {80.0, 90.0, 80.0, 90.0, 80.0, 90.0};
  // Bending +8, +10, +12 (10 +- 1.15: plain); steering +5, -15, +2 (-2.7 +- 6.2); overall 3.7 +- 4.0.
  const std::vector<double> plain = {88.0, 95.0, 90.0, 75.0, 92.0, 92.0};
  const auto c = clearGain(plain, base, 2);
  EXPECT_FALSE(c.by_overall) << c.overall.first << " +- " << c.overall.second;
  EXPECT_TRUE(c.by_one_output);
  EXPECT_TRUE(c.clear());
  const auto per = plsa::eval::perOutputPairedGains(plain, base, 2);
  ASSERT_EQ(per.size(), 2u);
  EXPECT_NEAR(per[0].first, 10.0, 1e-12);
  EXPECT_NEAR(per[1].first, -8.0 / 3.0, 1e-12);
  // Steering losing by more than its own standard error (-5, -6, -7): not kept.
  const std::vector<double> trades = {88.0, 85.0, 90.0, 84.0, 92.0, 83.0};
  EXPECT_FALSE(clearGain(trades, base, 2).clear());
  // Neither output plain (bending +1, -1, +3; steering +2, -2, +1): not kept.
  EXPECT_FALSE(clearGain({81.0, 92.0, 79.0, 88.0, 83.0, 91.0}, base, 2).clear());
  // Both gaining steadily: kept by the overall rule alone.
  const auto both = clearGain({82.0, 92.0, 82.5, 91.5, 81.5, 92.5}, base, 2);
  EXPECT_TRUE(both.by_overall);
  EXPECT_FALSE(both.by_one_output);
  // A plain bending gain with a larger steering loss loses overall: not kept.
  EXPECT_FALSE(clearGain({83.0, 70.0, 83.5, 71.0, 82.5, 69.0}, base, 2).clear());
}

TEST(PairedGain, FewerThanTwoPairsIsNoEvidenceAndUnpairedScoresThrow) {
  for (const auto& [a, b] : std::vector<std::pair<std::vector<double>, std::vector<double>>>{
           {{}, {}}, {{95.0}, {90.0}}, {{95.0, NAN}, {90.0, 91.0}}, {{95.0, 93.0}, {INFINITY, 91.0}}}) {
    const auto [gain, se] = plsa::eval::pairedGain(a, b);
    EXPECT_EQ(gain, 0.0) << a.size();
    EXPECT_TRUE(std::isinf(se)) << a.size();
    EXPECT_FALSE(gain > se);  // never kept on it
  }
  EXPECT_THROW(plsa::eval::pairedGain({1.0, 2.0}, {1.0}), std::invalid_argument);
}
