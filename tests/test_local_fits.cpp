// The paper's stages 1-6: step segmentation, local LTI fits, pole clustering; and the ARX baseline.
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

TEST(Segmentation, FindsOneInputStepsAndLevels) {
  Eigen::MatrixXd ref = Eigen::MatrixXd::Zero(600, 2);
  ref.block(100, 0, 500, 1).setConstant(0.2);
  ref.block(200, 1, 400, 1).setConstant(0.25);
  ref.block(300, 0, 300, 1).setConstant(0.3);
  ref.block(400, 0, 200, 1).setConstant(0.35);
  ref.block(400, 1, 200, 1).setConstant(0.3);  // both move at once: not a local step
  const auto segs = segmentSteps(ref, 0.01, 50);
  ASSERT_EQ(segs.size(), 3u);
  EXPECT_EQ(segs[1].input, 1);
  EXPECT_EQ(segs[1].begin, 200);
  EXPECT_EQ(segs[1].end, 300);
  EXPECT_TRUE(segs[2].rising());
  EXPECT_DOUBLE_EQ(segs[2].to, 0.3);
  const auto levels = referenceLevels(ref, 0.01, 50);
  EXPECT_EQ(levels[0], (std::vector<double>{0.0, 0.2, 0.3, 0.35}));
}

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

// Pure FKcM (its fuzzy criterion) matches or beats fuzzy c-means and k-means
// in all but one case; refined on rho (the default) in every case, and it
// then sits within a few percent of the global search.
TEST(PoleClustering, FkcmIsNoWorseThanFcmAndKmeansAndGlobalIsBest) {
  std::mt19937 rng(8);
  std::normal_distribution<double> n01;
  int fkcm_wins = 0, refined_wins = 0, cases = 0;
  for (int seed = 0; seed < 6; ++seed) {
    std::vector<C> poles;
    for (double c : {0.86, 0.9, 0.95, 0.985})
      for (int i = 0; i < 6; ++i) poles.emplace_back(std::min(0.998, c + 0.01 * n01(rng)), 0.0);
    ClusteringOptions o;
    o.centres = 3;
    const auto r = fkcmClustering(poles, o);
    o.refine_on_rho = false;
    const auto f = fkcmClustering(poles, o);
    const auto c = fuzzyCMeansClustering(poles, o);
    const auto k = kMeansClustering(poles, o);
    const auto g = globalRhoSearch(poles, o);
    ASSERT_EQ(f.centres.size(), 3u);
    ASSERT_EQ(r.centres.size(), 3u);
    EXPECT_NEAR(f.rho, decayRate(f.centres, poles), 1e-15);
    EXPECT_NEAR(r.rho, decayRate(r.centres, poles), 1e-15);
    EXPECT_LE(r.rho, f.rho);
    EXPECT_LE(r.rho, 1.05 * g.rho) << "seed " << seed;
    EXPECT_LE(g.rho, f.rho * (1 + 1e-9));
    EXPECT_LE(g.rho, std::min(c.rho, k.rho) * (1 + 1e-9));
    ++cases;
    if (f.rho <= std::min(c.rho, k.rho) * 1.0001) ++fkcm_wins;
    if (r.rho <= std::min(c.rho, k.rho) * 1.0001) ++refined_wins;
  }
  EXPECT_GE(fkcm_wins, cases - 1) << "FKcM should match or beat FCM and k-means on rho";
  EXPECT_EQ(refined_wins, cases) << "refined on rho, FKcM should match or beat FCM and k-means every time";
}

TEST(PoleClustering, ComplexPairsAndBadInput) {
  std::vector<C> poles = {C(0.8, 0.3), C(0.8, -0.3), C(0.82, 0.28), C(0.82, -0.28), C(0.9, 0), C(0.91, 0)};
  ClusteringOptions o;
  o.centres = 3;
  o.complex_pairs = 1;
  const auto f = fkcmClustering(poles, o);
  ASSERT_EQ(f.centres.size(), 3u);
  EXPECT_LT(f.rho, 0.05);
  const PoleSet ok(f.centres);  // a valid, conjugate-closed pole set
  EXPECT_EQ(ok.size(), 3);
  EXPECT_THROW(fkcmClustering({C(1.2, 0)}, o), std::invalid_argument);
  EXPECT_THROW(fkcmClustering({}, o), std::invalid_argument);
  for (double m : {1.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    o.fuzziness = m;
    EXPECT_THROW(fkcmClustering(poles, o), std::invalid_argument) << m;
  }
}

TEST(Arx, RecoversAKnownArxSystem) {
  std::mt19937 rng(6);
  std::normal_distribution<double> n01;
  const int T = 3000;
  Eigen::MatrixXd u(T, 1), y(T, 1);
  u(0, 0) = y(0, 0) = y(1, 0) = 0;
  for (int k = 1; k < T; ++k) u(k, 0) = n01(rng);
  for (int k = 2; k < T; ++k) y(k, 0) = 1.5 * y(k - 1, 0) - 0.6 * y(k - 2, 0) + 0.3 * u(k - 1, 0) + 0.1;
  const ArxModel m = ArxModel::fit({u}, {y}, 2, 1, 0.0);
  EXPECT_NEAR(m.theta(0, 0), 1.5, 1e-6);
  EXPECT_NEAR(m.theta(1, 0), -0.6, 1e-6);
  EXPECT_NEAR(m.theta(2, 0), 0.3, 1e-6);
  EXPECT_NEAR(m.theta(3, 0), 0.1, 1e-6);
  EXPECT_NEAR(fitOf(y.col(0), m.kStepAhead(u, y.col(0), 0, 20)), 100.0, 1e-6);
  EXPECT_NEAR(fitOf(y.col(0), m.simulate(u, y.col(0), 0)), 100.0, 1e-6);
}
