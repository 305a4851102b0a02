// Step 7: the coefficients by regularised least squares, their sample weights and fold sums.
#include "plsa/identify/lower_gram.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

TEST(CoefficientFit, RecoversKnownCoefficientsAndReportsEmptyRegions) {
  const DioPwlObfModel truth = knownModel();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  Eigen::MatrixXd u(4000, 1);
  for (int k = 0; k < 4000; ++k) u(k, 0) = k % 50 == 0 ? level(rng) : u(std::max(0, k - 1), 0);
  const Eigen::MatrixXd dy = eval::modelIncrements(truth, u);
  Eigen::MatrixXd y = dioIntegrate(dy);
  // Without regularisation, exact data give the exact coefficients.
  DioPwlObfModel fit = truth;
  CoefficientFitOptions exact;
  exact.ridge = 0.0;
  exact.pull_to_global = 0.0;
  fitCoefficients(fit, {u}, {y}, exact);
  EXPECT_LT((fit.coefficients[0][0] - truth.coefficients[0][0]).norm(), 1e-8);
  EXPECT_LT((fit.coefficients[1][0] - truth.coefficients[1][0]).norm(), 1e-8);
  // The default pull toward the global solution costs about a percent, no more.
  DioPwlObfModel pulled = truth;
  fitCoefficients(pulled, {u}, {y});
  EXPECT_LT((pulled.coefficients[1][0] - truth.coefficients[1][0]).norm(), 0.02 * truth.coefficients[1][0].norm());
  // Inputs confined below 0.5: the upper region has no data and must say so.
  Eigen::MatrixXd u_low = u * 0.45;
  Eigen::MatrixXd y_low = dioIntegrate(eval::modelIncrements(truth, u_low));
  DioPwlObfModel partial = truth;
  const auto rep = fitCoefficients(partial, {u_low}, {y_low});
  EXPECT_EQ(rep.regions_fallback, 1);
  EXPECT_EQ(partial.region_fits[1].fallback_from, 0);
  EXPECT_NE(rep.notes[0].find("too little data"), std::string::npos);
  EXPECT_EQ(partial.coefficients[1][0], partial.coefficients[0][0]);
  EXPECT_GT(partial.coefficients[1][0].norm(), 0.5);  // never silent zeros
}

// Two outputs (one thread each on the input side), noisy so that every subset
// of the samples gives different coefficients.
TEST(CoefficientFit, WeightsAndFoldSumsAgreeWithTheSamplesTheyStandFor) {
  const DioPwlObfModel truth = knownModel();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.05);
  const int T = 3000;
  Eigen::MatrixXd u(T, 1);
  for (int k = 0; k < T; ++k) u(k, 0) = k % 40 == 0 ? level(rng) : u(std::max(0, k - 1), 0);
  Eigen::MatrixXd y(T, 2);
  y.col(0) = dioIntegrate(eval::modelIncrements(truth, u)).col(0);
  y.col(1) = 0.5 * y.col(0).array().square();
  for (int k = 0; k < T; ++k) y.row(k) += Eigen::RowVector2d(noise(rng), noise(rng));
  Eigen::VectorXi fold(T);
  for (int k = 0; k < T; ++k) fold(k) = (k / 250) % 3;
  for (const ScheduleSide side : {ScheduleSide::kOutput, ScheduleSide::kInput}) {
    SCOPED_TRACE(side == ScheduleSide::kInput ? "input side" : "output side");
    DioPwlObfModel m = truth;
    m.outputs = {"y", "z"};
    m.poles = {truth.poles[0], {PoleSet::real({0.8, 0.5})}};
    m.schedule_side = side;
    auto stacked = [](const DioPwlObfModel& x) {
      Eigen::VectorXd c(2 * x.stackedCoefficients(0).size());
      c << x.stackedCoefficients(0), x.stackedCoefficients(1);
      return c;
    };
    // Weight 2 on a record is the record twice.
    DioPwlObfModel twice = m, weighted = m;
    fitCoefficients(twice, {u, u}, {y, y});
    fitCoefficients(weighted, {u}, {y}, {}, {Eigen::VectorXd::Constant(T, 2.0)});
    EXPECT_LT((stacked(twice) - stacked(weighted)).norm(), 1e-9 * stacked(twice).norm());
    // Leaving a fold out of the sums is weighting it 0, and it changes the fit.
    DioPwlObfModel all = m;
    fitCoefficients(all, {u}, {y});
    const CoefficientSums sums = coefficientSums(m, {eval::modelRegressors(m, u)}, {y}, {fold}, 3);
    DioPwlObfModel from_sums = m;
    solveCoefficients(from_sums, sums, -1);
    EXPECT_LT((stacked(from_sums) - stacked(all)).norm(), 1e-9 * stacked(all).norm());
    for (int f = 0; f < 3; ++f) {
      DioPwlObfModel left = m, zeroed = m;
      solveCoefficients(left, sums, f);
      fitCoefficients(zeroed, {u}, {y}, {}, {(fold.array() != f).cast<double>().matrix()});
      EXPECT_LT((stacked(left) - stacked(zeroed)).norm(), 1e-9 * stacked(all).norm()) << "fold " << f;
      EXPECT_GT((stacked(left) - stacked(all)).norm(), 1e-4 * stacked(all).norm()) << "fold " << f;
      const int counted = left.region_fits[0].samples + left.region_fits[1].samples;
      EXPECT_NEAR(counted, (fold.tail(T - 1).array() != f).count(), 1.0);
    }
    // Bad groups, folds and weights are named.
    Eigen::VectorXi bad = fold;
    bad(7) = 3;
    EXPECT_THROW(coefficientSums(m, {eval::modelRegressors(m, u)}, {y}, {bad}, 3), std::invalid_argument);
    DioPwlObfModel x = m;
    EXPECT_THROW(solveCoefficients(x, sums, 3), std::invalid_argument);
    Eigen::VectorXd negative = Eigen::VectorXd::Ones(T);
    negative(9) = -1.0;
    EXPECT_THROW(fitCoefficients(x, {u}, {y}, {}, {negative}), std::invalid_argument);
    EXPECT_THROW(fitCoefficients(x, {u}, {y}, {}, {Eigen::VectorXd::Ones(T - 1)}), std::invalid_argument);
  }
}

// The coefficient fit's Gram kernel against Eigen's product, on tiles of
// every shape it meets: columns not a multiple of the blocks, rows not a
// multiple of four, one row, one column; the strict upper triangle zero.
TEST(CoefficientFit, LowerGramIsTheTilesInnerProduct) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (const auto& [rows, cols] : std::vector<std::pair<int, int>>{{256, 145}, {7, 9}, {1, 3}, {33, 1}, {4, 4}}) {
    Eigen::MatrixXd p(rows, cols);
    for (int i = 0; i < p.size(); ++i) p(i) = normal(rng);
    Eigen::MatrixXd gram = Eigen::MatrixXd::Constant(3, 3, 7.0);  // resized and overwritten
    lowerGram(p, gram);
    ASSERT_EQ(gram.rows(), cols);
    ASSERT_EQ(gram.cols(), cols);
    const Eigen::MatrixXd expected = p.transpose() * p;
    for (int j = 0; j < cols; ++j)
      for (int i = 0; i < cols; ++i)
        if (i >= j)
          EXPECT_NEAR(gram(i, j), expected(i, j), 1e-12 * (1.0 + std::abs(expected(i, j)))) << i << "," << j;
        else
          EXPECT_EQ(gram(i, j), 0.0) << i << "," << j;
  }
}
