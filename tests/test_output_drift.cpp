// The sensor drift of the outputs: its removal and its estimate (plsa/identify/output_drift.hpp).
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

TEST(OutputDrift, RemovalIsALinearTrendAboutTheReferenceAndChecksItsInput) {
  Eigen::MatrixXd y(3, 2);
  y << 1, 10, 2, 20, 3, 30;
  const Eigen::VectorXd t = Eigen::Vector3d(0.0, 1.0, 2.0);
  EXPECT_DOUBLE_EQ(meanSampleTime({t}), 1.0);
  OutputDrift d;
  d.rate = {0.0, 0.5};
  d.reference_time_s = 1.0;
  EXPECT_FALSE(d.none());
  const Eigen::MatrixXd out = removeOutputDrift({y}, {t}, d)[0];
  EXPECT_EQ(out.col(0), y.col(0));
  EXPECT_DOUBLE_EQ(out(0, 1), 10.5);  // before the reference: the drift was below it
  EXPECT_DOUBLE_EQ(out(1, 1), 20.0);
  EXPECT_DOUBLE_EQ(out(2, 1), 29.5);
  d.rate = {0.5};
  EXPECT_THROW(removeOutputDrift({y}, {t}, d), std::invalid_argument);  // one rate for two outputs
  d.rate = {0.0, 0.5};
  EXPECT_THROW(removeOutputDrift({y}, {Eigen::Vector2d(0, 1)}, d), std::invalid_argument);
  // Output side: the level is not a function of the inputs.
  DioPwlObfModel m = knownModel();
  try {
    estimateOutputDrift(m, {Eigen::MatrixXd::Zero(3, m.inputCount())}, {Eigen::MatrixXd::Zero(3, m.outputCount())},
                        {t});
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("input-side"), std::string::npos) << e.what();
  }
}

// A model that is exactly right plus a known trend: the estimate must find
// the trend, skip an empty record, and give zero where nothing can show one.
TEST(OutputDrift, EstimateFindsAKnownTrendAndToleratesUninformativeData) {
  DioPwlObfModel truth = knownModel();
  truth.partition = PwlPartition::interpolated({}, {});  // one node: a linear input-side model
  truth.schedule_side = ScheduleSide::kInput;
  truth.coefficients = {{Eigen::Vector2d(1.5, -0.2)}};
  truth.region_fits = {RegionFit{}};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  Eigen::MatrixXd u(2000, 1);
  for (Eigen::Index k = 0; k < u.rows(); k += 100) u.middleRows(k, 100).setConstant(level(rng));
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(u.rows(), 0.0, 199.9);
  const Eigen::MatrixXd clean = eval::modelLevels(truth, u, eval::modelIncrements(truth, u));
  const double rate = 0.004;
  const Eigen::MatrixXd y = clean.array() + rate * (t.array() - t.mean());
  const std::vector<Eigen::MatrixXd> U{u, Eigen::MatrixXd(0, 1)}, Y{y, Eigen::MatrixXd(0, 1)};
  const std::vector<Eigen::VectorXd> T{t, Eigen::VectorXd(0)};
  const OutputDrift d = estimateOutputDrift(truth, U, Y, T);
  ASSERT_EQ(d.rate.size(), 1u);
  EXPECT_NEAR(d.rate[0], rate, 0.02 * rate);
  EXPECT_NEAR(d.reference_time_s, t.mean(), 1e-9);
  // Every sample at one time: no trend can show.
  const OutputDrift flat = estimateOutputDrift(truth, {u}, {y}, {Eigen::VectorXd::Constant(u.rows(), 3.0)});
  EXPECT_EQ(flat.rate[0], 0.0);
  // A late disturbance skews the trend unless its samples are weighted out.
  Eigen::MatrixXd bumped = y;
  bumped.bottomRows(300).array() += 2.0;
  Eigen::VectorXd keep = Eigen::VectorXd::Ones(u.rows());
  keep.tail(300).setZero();
  EXPECT_GT(estimateOutputDrift(truth, {u}, {bumped}, {t}).rate[0], 1.5 * rate);
  EXPECT_NEAR(estimateOutputDrift(truth, {u}, {bumped}, {t}, {}, 3, {keep}).rate[0], rate, 0.02 * rate);
}
