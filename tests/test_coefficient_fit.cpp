// Step 7: the coefficients by regularised least squares, the batch regressors and their fold sums.
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

TEST(CoefficientFit, RecoversKnownCoefficientsAndReportsEmptyRegions) {
  const DioPwlObfModel truth = knownModel();
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  Eigen::MatrixXd u(4000, 1);
  for (int k = 0; k < 4000; ++k) u(k, 0) = k % 50 == 0 ? level(rng) : u(std::max(0, k - 1), 0);
  const Eigen::MatrixXd dy = modelIncrements(truth, u);
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
  Eigen::MatrixXd y_low = dioIntegrate(modelIncrements(truth, u_low));
  DioPwlObfModel partial = truth;
  const auto rep = fitCoefficients(partial, {u_low}, {y_low});
  EXPECT_EQ(rep.regions_fallback, 1);
  EXPECT_EQ(partial.region_fits[1].fallback_from, 0);
  EXPECT_NE(rep.notes[0].find("too little data"), std::string::npos);
  EXPECT_EQ(partial.coefficients[1][0], partial.coefficients[0][0]);
  EXPECT_GT(partial.coefficients[1][0].norm(), 0.5);  // never silent zeros
}

// Input side over a 4 x 4 grid of nodes, visited in turn as a grid experiment
// does: over most tiles most nodes' regressors are zero (not yet visited) or
// decayed below rounding, and skipping them must change no increment or sum
// beyond rounding. Refilling a used ModelRegressors must equal a fresh one.
TEST(Regressors, SkippedNegligibleTilesChangeNoSumBeyondRounding) {
  DioPwlObfModel m;
  m.inputs = {"u1", "u2"};
  m.outputs = {"y", "z"};
  m.poles = {{PoleSet::real({0.9, 0.7}), PoleSet::real({0.85})}, {PoleSet::real({0.8}), PoleSet::real({0.9, 0.6})}};
  m.shaping.play = {{0.0}, {0.0}};
  m.partition = PwlPartition::interpolated({0, 1}, {{0.2, 0.4, 0.6, 0.8}, {0.2, 0.4, 0.6, 0.8}});
  m.schedule_side = ScheduleSide::kInput;
  const int R = m.partition.regionCount();
  ASSERT_EQ(R, 16);
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 1.0);
  m.coefficients.assign(static_cast<std::size_t>(R), {});
  for (auto& block : m.coefficients)
    for (int out = 0; out < 2; ++out) block.push_back(Eigen::VectorXd::NullaryExpr(3, [&] { return gauss(rng); }));
  m.region_fits.assign(static_cast<std::size_t>(R), RegionFit{});
  const int hold = 400, T = 16 * hold;
  Eigen::MatrixXd u(T, 2);
  for (int k = 0; k < T; ++k) u.row(k) << 0.2 + 0.2 * ((k / hold) % 4), 0.2 + 0.2 * (k / (4 * hold));
  Eigen::MatrixXd y = dioIntegrate(modelIncrements(m, u));
  for (Eigen::Index k = 0; k < y.size(); ++k) y.data()[k] += 0.01 * gauss(rng);

  const ModelRegressors sparse = modelRegressors(m, u);
  ModelRegressors dense = sparse;
  dense.live.clear();  // every node live: the plain dense sums and products
  ASSERT_EQ(sparse.live.size(), 2u);
  for (int out = 0; out < 2; ++out) {
    const auto& live = sparse.live[static_cast<std::size_t>(out)];
    EXPECT_EQ(live.rows(), (T + ModelRegressors::kTileRows - 1) / ModelRegressors::kTileRows);
    EXPECT_EQ(live.cols(), R);
    EXPECT_LT(live.cast<double>().mean(), 0.5) << "a grid experiment leaves most tiles' nodes negligible";
    EXPECT_TRUE(live.col(R - 1).head(3).isConstant(false)) << "the last node is not visited before the end";
  }
  const Eigen::MatrixXd di_sparse = modelIncrements(m, sparse), di_dense = modelIncrements(m, dense);
  EXPECT_LT((di_sparse - di_dense).cwiseAbs().maxCoeff(), 1e-12 * di_dense.cwiseAbs().maxCoeff());
  Eigen::VectorXi fold(T);
  for (int k = 0; k < T; ++k) fold(k) = (k / 300) % 3;
  const CoefficientSums s_sparse = coefficientSums(m, {sparse}, {y}, {fold}, 3);
  const CoefficientSums s_dense = coefficientSums(m, {dense}, {y}, {fold}, 3);
  // The sums themselves (lower triangles: the only part kept) agree to rounding;
  // solutions would add the conditioning of a fold's normal equations.
  for (int g = 0; g < 3; ++g)
    for (std::size_t out = 0; out < 2; ++out) {
      const Eigen::MatrixXd& Js = s_sparse.groups[static_cast<std::size_t>(g)].J[out];
      const Eigen::MatrixXd& Jd = s_dense.groups[static_cast<std::size_t>(g)].J[out];
      const Eigen::MatrixXd diff =
          Eigen::MatrixXd(Js.triangularView<Eigen::Lower>()) - Eigen::MatrixXd(Jd.triangularView<Eigen::Lower>());
      EXPECT_LT(diff.cwiseAbs().maxCoeff(), 1e-12 * Jd.cwiseAbs().maxCoeff()) << "group " << g << ", output " << out;
      const Eigen::VectorXd& hs = s_sparse.groups[static_cast<std::size_t>(g)].Jh[out];
      const Eigen::VectorXd& hd = s_dense.groups[static_cast<std::size_t>(g)].Jh[out];
      EXPECT_LT((hs - hd).cwiseAbs().maxCoeff(), 1e-12 * hd.cwiseAbs().maxCoeff())
          << "group " << g << ", output " << out;
    }
  DioPwlObfModel a = m, b = m;
  solveCoefficients(a, s_sparse, -1);
  solveCoefficients(b, s_dense, -1);
  for (int out = 0; out < 2; ++out)
    EXPECT_LT((a.stackedCoefficients(out) - b.stackedCoefficients(out)).norm(),
              1e-9 * b.stackedCoefficients(out).norm());

  // A used ModelRegressors, first filled from another record, refills to the fresh one.
  ModelRegressors reused = modelRegressors(m, Eigen::MatrixXd(u.topRows(T / 2).reverse()));
  modelRegressors(m, u, reused);
  for (std::size_t out = 0; out < 2; ++out) {
    EXPECT_EQ(reused.phi[out], sparse.phi[out]);
    EXPECT_TRUE((reused.live[out] == sparse.live[out]).all());
    EXPECT_EQ(reused.level0[out], sparse.level0[out]);
  }
  ASSERT_EQ(reused.schedule.size(), sparse.schedule.size());
  for (std::size_t k = 0; k < sparse.schedule.size(); ++k) {
    ASSERT_EQ(reused.schedule[k].count, sparse.schedule[k].count);
    for (int c = 0; c < sparse.schedule[k].count; ++c)
      EXPECT_EQ(reused.schedule[k].weight[static_cast<std::size_t>(c)],
                sparse.schedule[k].weight[static_cast<std::size_t>(c)]);
  }
  const ModelRegressors empty = modelRegressors(m, Eigen::MatrixXd(0, 2));
  modelRegressors(m, Eigen::MatrixXd(0, 2), reused);
  EXPECT_EQ(reused.live[0].rows(), 0);
  EXPECT_EQ(empty.phi[0].rows(), 0);
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
  y.col(0) = dioIntegrate(modelIncrements(truth, u)).col(0);
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
    const CoefficientSums sums = coefficientSums(m, {modelRegressors(m, u)}, {y}, {fold}, 3);
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
    EXPECT_THROW(coefficientSums(m, {modelRegressors(m, u)}, {y}, {bad}, 3), std::invalid_argument);
    DioPwlObfModel x = m;
    EXPECT_THROW(solveCoefficients(x, sums, 3), std::invalid_argument);
    Eigen::VectorXd negative = Eigen::VectorXd::Ones(T);
    negative(9) = -1.0;
    EXPECT_THROW(fitCoefficients(x, {u}, {y}, {}, {negative}), std::invalid_argument);
    EXPECT_THROW(fitCoefficients(x, {u}, {y}, {}, {Eigen::VectorXd::Ones(T - 1)}), std::invalid_argument);
  }
}
