// The tied slow pole (slow_mode_tie.hpp): its coefficient map realises the
// lagged response it stands for, and the fit finds the fraction it was made with.
#include <complex>
#include <random>

#include "plsa/identify/slow_mode_tie.hpp"
#include "plsa/obf/obf_bank.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

namespace {

constexpr double kSlow = 0.995;

std::vector<std::complex<double>> withSlow(std::vector<std::complex<double>> p) {
  p.emplace_back(kSlow, 0.0);
  return p;
}

// Two inputs (the first with two play channels), two outputs whose banks
// differ (a complex pair in one), input side on a two-cell grid, every bank
// carrying the slow pole last.
DioPwlObfModel slowModel() {
  DioPwlObfModel m;
  m.inputs = {"u", "v"};
  m.outputs = {"y", "z"};
  m.poles = {{PoleSet(withSlow({0.9, 0.7})), PoleSet(withSlow({0.8}))},
             {PoleSet(withSlow({{0.85, 0.1}, {0.85, -0.1}})), PoleSet(withSlow({0.6, 0.3}))}};
  m.shaping.play = {{0.0, 0.1}, {0.0}};
  m.partition = PwlPartition::interpolated({0}, {{0.2, 0.8}});
  m.schedule_side = ScheduleSide::kInput;
  m.region_fits = {RegionFit{}, RegionFit{}};
  return m;
}

// Every region's coefficients for the model without the slow pole, drawn at
// random, mapped onto the model with it at fractions `alpha`.
DioPwlObfModel tiedTruth(const TiedSlowMode& tie, const std::vector<double>& alpha, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  DioPwlObfModel m = slowModel();
  m.coefficients.assign(2, std::vector<Eigen::VectorXd>(2));
  for (auto& region : m.coefficients)
    for (std::size_t o = 0; o < 2; ++o) {
      Eigen::VectorXd c(tie.fast.regressorSize(static_cast<int>(o)));
      for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = g(rng);
      region[o] = tie.blocks[o].at(alpha[o]) * c;
    }
  return m;
}

// Held random levels on both inputs, the outputs the model gives.
struct Record {
  Eigen::MatrixXd u, y;
};
Record recordOf(const DioPwlObfModel& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> level(0.0, 1.0);
  Eigen::MatrixXd u(12000, 2);
  for (Eigen::Index k = 0; k < u.rows(); ++k)
    for (int j = 0; j < 2; ++j) u(k, j) = k % (150 + 70 * j) == 0 ? level(rng) : u(std::max<Eigen::Index>(0, k - 1), j);
  return {u, dioIntegrate(eval::modelIncrements(m, u))};
}

}  // namespace

// On every bank, at points of the plane off the poles, the tied coefficients'
// transfer function is F(z) times the fast one, F = 1 + alpha (1 - p)/(z - p).
TEST(SlowModeTie, TiedCoefficientsRealiseTheLaggedResponse) {
  const DioPwlObfModel m = slowModel();
  const TiedSlowMode tie = tiedSlowMode(m, kSlow);
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  const double alpha = 0.35;
  for (int o = 0; o < 2; ++o) {
    const auto oo = static_cast<std::size_t>(o);
    ASSERT_EQ(tie.blocks[oo].A.rows(), m.regressorSize(o));
    ASSERT_EQ(tie.blocks[oo].A.cols(), m.regressorSize(o) - 3);  // one slow basis function per bank, three banks
    Eigen::VectorXd c(tie.blocks[oo].A.cols());
    for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = g(rng);
    const Eigen::VectorXd tied = tie.blocks[oo].at(alpha) * c;
    for (const std::complex<double> z : {std::complex<double>(1.0, 0.0), std::polar(1.0, 0.05), std::polar(1.0, 2.0),
                                         std::complex<double>(0.4, 0.5), std::complex<double>(-0.8, 0.0)}) {
      const std::complex<double> F = 1.0 + alpha * (1.0 - kSlow) / (z - kSlow);
      Eigen::Index at_slow = 0, at_fast = 0;
      for (std::size_t j = 0; j < 2; ++j)
        for (std::size_t ch = 0; ch < m.shaping.play[j].size(); ++ch) {
          const Eigen::VectorXcd bs = ObfBank<>(m.poles[oo][j]).transfer(z);
          const Eigen::VectorXcd bf = ObfBank<>(tie.fast.poles[oo][j]).transfer(z);
          const std::complex<double> slow =
              bs.transpose() * tied.segment(at_slow, bs.size()).cast<std::complex<double>>();
          const std::complex<double> fast = bf.transpose() * c.segment(at_fast, bf.size()).cast<std::complex<double>>();
          EXPECT_LT(std::abs(slow - F * fast), 1e-9 * (1.0 + std::abs(F * fast))) << "output " << o << " bank " << j;
          at_slow += bs.size();
          at_fast += bf.size();
        }
    }
  }
  DioPwlObfModel missing = m;
  missing.poles[1][1] = PoleSet::real({0.6, 0.3});
  EXPECT_THROW(tiedSlowMode(missing, kSlow), std::invalid_argument);
}

// Exact data from a tied model: the fit recovers the fractions, one per
// output or (shared) one between them, and the coefficients.
TEST(SlowModeTie, FitRecoversTheFractionsItWasMadeWith) {
  const TiedSlowMode tie = tiedSlowMode(slowModel(), kSlow);
  CoefficientFitOptions exact;
  exact.ridge = 0.0;
  exact.pull_to_global = 0.0;
  exact.slow_mode = {kSlow, false};
  const DioPwlObfModel truth = tiedTruth(tie, {0.3, -0.2}, 7);
  const Record r = recordOf(truth, 11);
  DioPwlObfModel each = slowModel();
  const CoefficientFitReport rep = fitCoefficients(each, {r.u}, {r.y}, exact);
  ASSERT_EQ(rep.slow_fraction.size(), 2u);
  EXPECT_NEAR(rep.slow_fraction[0], 0.3, 1e-6);
  EXPECT_NEAR(rep.slow_fraction[1], -0.2, 1e-6);
  for (std::size_t l = 0; l < 2; ++l)
    for (std::size_t o = 0; o < 2; ++o)
      EXPECT_LT((each.coefficients[l][o] - truth.coefficients[l][o]).norm(), 1e-6 * truth.coefficients[l][o].norm());
  // One fraction for both: it must fall between the two, and fit worse than each its own.
  exact.slow_mode.shared = true;
  DioPwlObfModel shared = slowModel();
  const CoefficientFitReport one = fitCoefficients(shared, {r.u}, {r.y}, exact);
  ASSERT_EQ(one.slow_fraction.size(), 2u);
  EXPECT_EQ(one.slow_fraction[0], one.slow_fraction[1]);
  EXPECT_GT(one.slow_fraction[0], -0.2 + 1e-3);
  EXPECT_LT(one.slow_fraction[0], 0.3 - 1e-3);
  const Eigen::MatrixXd miss = dioIntegrate(eval::modelIncrements(shared, r.u)) - r.y;
  EXPECT_GT(miss.norm(), 1e-3 * r.y.norm());
  // A model made shared is fitted exactly by the shared form.
  const DioPwlObfModel same = tiedTruth(tie, {0.25, 0.25}, 8);
  const Record s = recordOf(same, 12);
  DioPwlObfModel back = slowModel();
  EXPECT_NEAR(fitCoefficients(back, {s.u}, {s.y}, exact).slow_fraction[1], 0.25, 1e-6);
  // Without a tie the fit reports no fraction.
  DioPwlObfModel free_fit = slowModel();
  exact.slow_mode = {};
  EXPECT_TRUE(fitCoefficients(free_fit, {s.u}, {s.y}, exact).slow_fraction.empty());
}
