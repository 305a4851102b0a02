// Tied slow poles (slow_mode_tie.hpp): the coefficient map realises the lagged
// responses it stands for, and the fit finds the fractions it was made with;
// identification chooses them for creep (slow_pole_search.cpp).
#include <complex>
#include <random>

#include "plsa/identify/baselines.hpp"
#include "plsa/identify/slow_fraction_levels.hpp"
#include "plsa/identify/slow_mode_tie.hpp"
#include "plsa/obf/obf_bank.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

namespace {

constexpr double kSlow = 0.995;
constexpr double kSlower = 0.999;

Eigen::VectorXd fraction(double a) { return Eigen::VectorXd::Constant(1, a); }

// Two inputs (the first with two play channels), two outputs whose banks
// differ (a complex pair in one), input side on a two-cell grid, every bank
// carrying the slow poles `slow` last.
DioPwlObfModel slowModel(const std::vector<double>& slow = {kSlow}) {
  const auto withSlow = [&](std::vector<std::complex<double>> p) {
    for (double s : slow) p.emplace_back(s, 0.0);
    return PoleSet(p);
  };
  DioPwlObfModel m;
  m.inputs = {"u", "v"};
  m.outputs = {"y", "z"};
  m.poles = {{withSlow({0.9, 0.7}), withSlow({0.8})}, {withSlow({{0.85, 0.1}, {0.85, -0.1}}), withSlow({0.6, 0.3})}};
  m.shaping.play = {{0.0, 0.1}, {0.0}};
  m.partition = PwlPartition::interpolated({0}, {{0.2, 0.8}});
  m.schedule_side = ScheduleSide::kInput;
  m.region_fits = {RegionFit{}, RegionFit{}};
  return m;
}

// Every region's coefficients for the model without the slow pole, drawn at
// random, mapped onto the model with it at fractions `alpha`.
DioPwlObfModel tiedTruth(const TiedSlowMode& tie, const SlowFractions& alpha, unsigned seed,
                         const std::vector<double>& slow = {kSlow}) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  DioPwlObfModel m = slowModel(slow);
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
// transfer function is F(z) times the fast one,
// F = 1 + sum_m alpha_m (1 - p_m)/(z - p_m): one slow pole, and two.
void expectLaggedResponse(const std::vector<double>& slow, const Eigen::VectorXd& alpha) {
  const DioPwlObfModel m = slowModel(slow);
  const TiedSlowMode tie = tiedSlowMode(m, slow);
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int o = 0; o < 2; ++o) {
    const auto oo = static_cast<std::size_t>(o);
    ASSERT_EQ(tie.blocks[oo].A.rows(), m.regressorSize(o));
    // One slow basis function per slow pole and bank, three banks.
    ASSERT_EQ(tie.blocks[oo].A.cols(), m.regressorSize(o) - 3 * static_cast<int>(slow.size()));
    Eigen::VectorXd c(tie.blocks[oo].A.cols());
    for (Eigen::Index i = 0; i < c.size(); ++i) c(i) = g(rng);
    const Eigen::VectorXd tied = tie.blocks[oo].at(alpha) * c;
    for (const std::complex<double> z : {std::complex<double>(1.0, 0.0), std::polar(1.0, 0.05), std::polar(1.0, 2.0),
                                         std::complex<double>(0.4, 0.5), std::complex<double>(-0.8, 0.0)}) {
      std::complex<double> F = 1.0;
      for (std::size_t k = 0; k < slow.size(); ++k)
        F += alpha(static_cast<Eigen::Index>(k)) * (1.0 - slow[k]) / (z - slow[k]);
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
}

TEST(SlowModeTie, TiedCoefficientsRealiseTheLaggedResponse) {
  expectLaggedResponse({kSlow}, fraction(0.35));
  expectLaggedResponse({kSlow, kSlower}, Eigen::Vector2d(0.35, -0.15));
  DioPwlObfModel missing = slowModel();
  missing.poles[1][1] = PoleSet::real({0.6, 0.3});
  EXPECT_THROW(tiedSlowMode(missing, {kSlow}), std::invalid_argument);
  EXPECT_THROW(tiedSlowMode(slowModel({kSlow}), {kSlow, kSlower}), std::invalid_argument);       // one not carried
  EXPECT_THROW(tiedSlowMode(slowModel({kSlow, kSlow}), {kSlow, kSlow}), std::invalid_argument);  // the same twice
  EXPECT_THROW(tiedSlowMode(slowModel(), {}), std::invalid_argument);
}

// Exact data from a tied model: the fit recovers the fractions, one per
// output or (shared) one between them, and the coefficients.
TEST(SlowModeTie, FitRecoversTheFractionsItWasMadeWith) {
  const TiedSlowMode tie = tiedSlowMode(slowModel(), {kSlow});
  CoefficientFitOptions exact;
  exact.ridge = 0.0;
  exact.pull_to_global = 0.0;
  exact.slow_mode = {{kSlow}, false};
  const DioPwlObfModel truth = tiedTruth(tie, {fraction(0.3), fraction(-0.2)}, 7);
  const Record r = recordOf(truth, 11);
  DioPwlObfModel each = slowModel();
  const CoefficientFitReport rep = fitCoefficients(each, {r.u}, {r.y}, exact);
  ASSERT_EQ(rep.slow_fraction.size(), 2u);
  EXPECT_NEAR(rep.slow_fraction[0](0), 0.3, 1e-6);
  EXPECT_NEAR(rep.slow_fraction[1](0), -0.2, 1e-6);
  for (std::size_t l = 0; l < 2; ++l)
    for (std::size_t o = 0; o < 2; ++o)
      EXPECT_LT((each.coefficients[l][o] - truth.coefficients[l][o]).norm(), 1e-6 * truth.coefficients[l][o].norm());
  // One fraction for both: it must fall between the two, and fit worse than each its own.
  exact.slow_mode.shared = true;
  DioPwlObfModel shared = slowModel();
  const CoefficientFitReport one = fitCoefficients(shared, {r.u}, {r.y}, exact);
  ASSERT_EQ(one.slow_fraction.size(), 2u);
  EXPECT_EQ(one.slow_fraction[0], one.slow_fraction[1]);
  EXPECT_GT(one.slow_fraction[0](0), -0.2 + 1e-3);
  EXPECT_LT(one.slow_fraction[0](0), 0.3 - 1e-3);
  const Eigen::MatrixXd miss = dioIntegrate(eval::modelIncrements(shared, r.u)) - r.y;
  EXPECT_GT(miss.norm(), 1e-3 * r.y.norm());
  // A model made shared is fitted exactly by the shared form.
  const DioPwlObfModel same = tiedTruth(tie, {fraction(0.25), fraction(0.25)}, 8);
  const Record s = recordOf(same, 12);
  DioPwlObfModel back = slowModel();
  EXPECT_NEAR(fitCoefficients(back, {s.u}, {s.y}, exact).slow_fraction[1](0), 0.25, 1e-6);
  // Without a tie the fit reports no fraction.
  DioPwlObfModel free_fit = slowModel();
  exact.slow_mode = {};
  EXPECT_TRUE(fitCoefficients(free_fit, {s.u}, {s.y}, exact).slow_fraction.empty());
}

// Two slow poles: each output's pair of fractions and the coefficients are
// recovered from exact data; the same data fitted with one slow pole miss.
TEST(SlowModeTie, FitRecoversTwoSlowPolesFractions) {
  const std::vector<double> slow = {kSlow, kSlower};
  const TiedSlowMode tie = tiedSlowMode(slowModel(slow), slow);
  CoefficientFitOptions exact;
  exact.ridge = 0.0;
  exact.pull_to_global = 0.0;
  exact.slow_mode = {slow, false};
  const DioPwlObfModel truth = tiedTruth(tie, {Eigen::Vector2d(0.3, 0.1), Eigen::Vector2d(-0.1, 0.2)}, 9, slow);
  const Record r = recordOf(truth, 13);
  DioPwlObfModel two = slowModel(slow);
  const CoefficientFitReport rep = fitCoefficients(two, {r.u}, {r.y}, exact);
  ASSERT_EQ(rep.slow_fraction.size(), 2u);
  ASSERT_EQ(rep.slow_fraction[0].size(), 2);
  EXPECT_LT((rep.slow_fraction[0] - Eigen::Vector2d(0.3, 0.1)).norm(), 1e-6);
  EXPECT_LT((rep.slow_fraction[1] - Eigen::Vector2d(-0.1, 0.2)).norm(), 1e-6);
  for (std::size_t l = 0; l < 2; ++l)
    for (std::size_t o = 0; o < 2; ++o)
      EXPECT_LT((two.coefficients[l][o] - truth.coefficients[l][o]).norm(), 1e-6 * truth.coefficients[l][o].norm());
  DioPwlObfModel one = slowModel();
  exact.slow_mode = {{kSlow}, false};
  fitCoefficients(one, {r.u}, {r.y}, exact);
  EXPECT_GT((dioIntegrate(eval::modelIncrements(one, r.u)) - r.y).norm(), 1e-3 * r.y.norm());
}

// Given the fast coefficients, the simulated level is affine in the
// fractions: one level step from zero lands on the fractions the data were
// made with, one per output or (shared) one set, and reports the misfit it
// started from.
TEST(SlowModeTie, LevelStepRecoversTheFractionsFromTheFastCoefficients) {
  const std::vector<double> slow = {kSlow, kSlower};
  TiedSlowMode tie = tiedSlowMode(slowModel(slow), slow);
  std::mt19937 rng(21);
  std::normal_distribution<double> g(0.0, 1.0);
  tie.fast.coefficients.assign(2, std::vector<Eigen::VectorXd>(2));
  for (auto& region : tie.fast.coefficients)
    for (std::size_t o = 0; o < 2; ++o) {
      region[o].resize(tie.fast.regressorSize(static_cast<int>(o)));
      for (Eigen::Index i = 0; i < region[o].size(); ++i) region[o](i) = g(rng);
    }
  const SlowFractions truth = {Eigen::Vector2d(0.3, 0.1), Eigen::Vector2d(-0.1, 0.2)};
  DioPwlObfModel made = slowModel(slow);
  made.coefficients = tie.fast.coefficients;
  for (auto& region : made.coefficients)
    for (std::size_t o = 0; o < 2; ++o) region[o] = tie.blocks[o].at(truth[o]) * region[o];
  const Record r = recordOf(made, 23);
  const std::vector<Eigen::MatrixXd> U{r.u}, Y{r.y};
  const SampleWeights none;
  const SlowFractions zero(2, Eigen::Vector2d::Zero());
  const LevelFractionStep each = levelFractionStep(tie, slowModel(slow), zero, {U, Y, none}, false);
  EXPECT_LT((each.alpha[0] - truth[0]).norm(), 1e-6);
  EXPECT_LT((each.alpha[1] - truth[1]).norm(), 1e-6);
  EXPECT_GT(each.misfit, 1e-3 * r.y.squaredNorm());
  EXPECT_LT(levelFractionStep(tie, slowModel(slow), truth, {U, Y, none}, false).misfit, 1e-12 * r.y.squaredNorm());
  // Weight 0 leaves samples out: the second half alone gives the same answer.
  SampleWeights half{Eigen::VectorXd::Zero(r.u.rows())};
  half[0].tail(r.u.rows() / 2).setOnes();
  EXPECT_LT((levelFractionStep(tie, slowModel(slow), zero, {U, Y, half}, false).alpha[1] - truth[1]).norm(), 1e-6);
  // Shared: one set between the two outputs', not either's.
  const LevelFractionStep one = levelFractionStep(tie, slowModel(slow), zero, {U, Y, none}, true);
  EXPECT_EQ(one.alpha[0], one.alpha[1]);
  EXPECT_GT((one.alpha[0] - truth[0]).norm(), 1e-3);
  EXPECT_GT((one.alpha[0] - truth[1]).norm(), 1e-3);
}

// Creep on two time scales fitted with one slow pole: no fraction is exact,
// and the increments' weigh the fast response's small errors as much as the
// creep. The level step trades them for the simulated level: the model kept
// simulates the training record better (here by 23%; on a new record of the
// same kind it is 5% worse, so the held-out choice of the slow pole, not
// this fit, judges what generalises).
TEST(SlowModeTie, LevelFitSimulatesTheTrainingRecordBetterWhenTheTieIsInexact) {
  const std::vector<double> slow = {kSlow, kSlower};
  const DioPwlObfModel truth =
      tiedTruth(tiedSlowMode(slowModel(slow), slow), {Eigen::Vector2d(0.3, 0.2), Eigen::Vector2d(-0.1, 0.25)}, 9, slow);
  const Record train = recordOf(truth, 13);
  CoefficientFitOptions o;
  o.slow_mode = {{kSlow}, false, false};
  DioPwlObfModel on_increments = slowModel();
  const SlowFractions inc = fitCoefficients(on_increments, {train.u}, {train.y}, o).slow_fraction;
  o.slow_mode.fractions_on_levels = true;
  DioPwlObfModel on_level = slowModel();
  const SlowFractions lev = fitCoefficients(on_level, {train.u}, {train.y}, o).slow_fraction;
  EXPECT_GT((lev[0] - inc[0]).norm() + (lev[1] - inc[1]).norm(), 1e-3);
  // The record's outputs start at 0, not settled: its level fitted.
  const auto simulationMisfit = [&](const DioPwlObfModel& m) {
    const Eigen::MatrixXd e = train.y - eval::modelLevels(m, train.u);
    return (e.rowwise() - e.colwise().mean()).squaredNorm();
  };
  EXPECT_LT(simulationMisfit(on_level), 0.9 * simulationMisfit(on_increments));
}

namespace {

// Three folds of 400-sample chunks over a record of an inexact tie (two
// slow poles fitted with one), the first 500 samples a fourth group every
// fold fits (a search window's warm-up).
struct FoldCase {
  std::vector<Eigen::MatrixXd> U, Y;
  CoefficientSums sums;
  std::vector<SampleWeights> W;
};
FoldCase foldCase() {
  const std::vector<double> slow = {kSlow, kSlower};
  const DioPwlObfModel truth =
      tiedTruth(tiedSlowMode(slowModel(slow), slow), {Eigen::Vector2d(0.3, 0.2), Eigen::Vector2d(-0.1, 0.25)}, 9, slow);
  const Record train = recordOf(truth, 13);
  FoldCase c{{train.u}, {train.y}, {}, std::vector<SampleWeights>(3)};
  Eigen::VectorXi group(train.u.rows());
  for (Eigen::Index k = 0; k < group.size(); ++k) group(k) = k < 500 ? 3 : static_cast<int>((k / 400) % 3);
  c.sums = coefficientSums(slowModel(), c.U, c.Y, {group}, 4);
  for (int f = 0; f < 3; ++f) c.W[static_cast<std::size_t>(f)] = {(group.array() != f).cast<double>().matrix()};
  return c;
}

}  // namespace

// Cross-validation solves its folds together (solveFoldCoefficients): the
// level rounds simulate every fold in one pass, the last round the misfit
// alone. Each fold's fit is the one it gets alone, to the bit, per-output
// and shared fractions, and the level step moved the fractions off the
// increments' (the tie is inexact).
TEST(SlowModeTie, FoldFitsSolvedTogetherAreEachFoldsOwnFit) {
  const FoldCase c = foldCase();
  for (const bool shared : {false, true}) {
    CoefficientFitOptions o;
    o.slow_mode = {{kSlow}, shared, true};
    std::vector<DioPwlObfModel> together(3, slowModel());
    const std::vector<CoefficientFitReport> reports = solveFoldCoefficients(together, c.sums, o, {c.U, c.Y, c.W});
    ASSERT_EQ(reports.size(), 3u);
    for (int f = 0; f < 3; ++f) {
      const auto ff = static_cast<std::size_t>(f);
      DioPwlObfModel alone = slowModel();
      const LevelRecords records{c.U, c.Y, c.W[ff]};
      const CoefficientFitReport r = solveCoefficients(alone, c.sums, f, o, &records);
      for (std::size_t region = 0; region < alone.coefficients.size(); ++region)
        for (std::size_t out = 0; out < 2; ++out)
          EXPECT_EQ(together[ff].coefficients[region][out], alone.coefficients[region][out]) << "fold " << f;
      for (std::size_t out = 0; out < 2; ++out) EXPECT_EQ(reports[ff].slow_fraction[out], r.slow_fraction[out]);
      o.slow_mode.fractions_on_levels = false;
      DioPwlObfModel increments = slowModel();
      const CoefficientFitReport inc = solveCoefficients(increments, c.sums, f, o);
      o.slow_mode.fractions_on_levels = true;
      EXPECT_GT((inc.slow_fraction[0] - r.slow_fraction[0]).norm() + (inc.slow_fraction[1] - r.slow_fraction[1]).norm(),
                1e-4)
          << "fold " << f << (shared ? ", shared" : "");
    }
    EXPECT_THROW(solveFoldCoefficients(together, c.sums, o, {c.U, c.Y, std::vector<SampleWeights>(2)}),
                 std::invalid_argument);
  }
  std::vector<DioPwlObfModel> mixed{slowModel(), slowModel({kSlow, kSlower}), slowModel()};
  CoefficientFitOptions o;
  o.slow_mode = {{kSlow}, false, true};
  EXPECT_THROW(solveFoldCoefficients(mixed, c.sums, o, {c.U, c.Y, c.W}), std::invalid_argument);
}

// A misfit-only query gives the misfit of the step's query and no step; a
// query answered among others is answered as alone.
TEST(SlowModeTie, LevelStepsAnsweredTogetherAreAnsweredAsAlone) {
  const FoldCase c = foldCase();
  TiedSlowMode tie = tiedSlowMode(slowModel(), {kSlow});
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  tie.fast.coefficients.assign(2, std::vector<Eigen::VectorXd>(2));
  for (auto& region : tie.fast.coefficients)
    for (std::size_t out = 0; out < 2; ++out)
      region[out] = Eigen::VectorXd::NullaryExpr(tie.fast.regressorSize(static_cast<int>(out)), [&] { return g(rng); });
  const SlowFractions at = {fraction(0.05), fraction(-0.02)};
  for (const bool shared : {false, true}) {
    const std::vector<LevelFractionStep> steps = levelFractionSteps(
        slowModel(), {{tie, at, c.W[0], true}, {tie, at, c.W[0], false}, {tie, at, c.W[1], true}}, c.U, c.Y, shared);
    ASSERT_EQ(steps.size(), 3u);
    EXPECT_EQ(steps[0].misfit, steps[1].misfit);
    EXPECT_NE(steps[0].alpha[0], at[0]);
    EXPECT_EQ(steps[1].alpha[0], at[0]);
    EXPECT_EQ(steps[1].alpha[1], at[1]);
    const LevelFractionStep alone = levelFractionStep(tie, slowModel(), at, {c.U, c.Y, c.W[1]}, shared);
    EXPECT_EQ(steps[2].misfit, alone.misfit);
    for (std::size_t out = 0; out < 2; ++out) EXPECT_EQ(steps[2].alpha[out], alone.alpha[out]);
  }
  EXPECT_TRUE(levelFractionSteps(slowModel(), {}, c.U, c.Y, false).empty());
}

// Creep (15%, 8 s) is far slower than the grid's step responses, so the
// local fits never see it; the extra pole is chosen on held-out simulation.
TEST(Pipeline, SlowPoleIsChosenForCreepAndLiftsTheSimulation) {
  sim::SimConfig creep;
  for (const std::string& e : sim::effectNames()) creep.setEffectEnabled(e, false);
  creep.setEffectEnabled("creep", true);
  creep.creep.fraction = 0.15;
  sim::ExperimentOptions eo;
  sim::Actuator a(creep, 1), b(creep, 2);
  const io::Log train = sim::runExperiment(a, sim::gridExperiment(eo));
  const io::Log val = sim::runExperiment(b, sim::joystickExperiment(eo));
  IdentifyOptions o;
  o.play_candidates = {{0.0}};
  o.play_bank_candidates = {};  // no play at all: the slow pole alone is compared
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  o.scheduling = SchedulingChoice::kInputSide;
  o.slow_pole_candidates = {};
  const DioPwlObfModel without = identifyModel({train}, o);
  o.slow_pole_candidates = {2.0, 8.0, 30.0};
  IdentifyReport rep;
  const DioPwlObfModel with = identifyModel({train}, o, &rep);
  ASSERT_EQ(rep.slow_pole_scores.size(), 4u);
  EXPECT_EQ(rep.slow_pole_scores[0].first, 0.0);
  // Kept by the one-standard-error rule: the best gain over none, its error over folds and outputs.
  double best = -INFINITY;
  for (std::size_t k = 1; k < rep.slow_pole_scores.size(); ++k) best = std::max(best, rep.slow_pole_scores[k].second);
  EXPECT_NEAR(rep.slow_pole_gain.first, best - rep.slow_pole_scores[0].second, 1e-9);
  EXPECT_GT(rep.slow_pole_gain.second, 0.0);
  EXPECT_GT(rep.slow_pole_gain.first, rep.slow_pole_gain.second);
  // The progress line gives the gain per output as well.
  const auto line = std::find_if(rep.lines.begin(), rep.lines.end(), [](const std::string& l) {
    return l.find("slow pole in every bank") != std::string::npos;
  });
  ASSERT_NE(line, rep.lines.end());
  for (const std::string& out : with.outputs) EXPECT_NE(line->find(out + " "), std::string::npos) << *line;
  EXPECT_EQ(with.poles[0][0].size(), without.poles[0][0].size() + 1);
  // One time scale: a second slow pole beside it (2 or 30 s) is tried and
  // not kept, its best gain over 8 s alone within one standard error.
  ASSERT_EQ(rep.second_slow_pole_scores.size(), 3u);
  EXPECT_EQ(rep.second_slow_pole_scores[0].second, rep.slow_pole_scores[2].second);  // 8 s alone, as scored first
  const double second_best = std::max(rep.second_slow_pole_scores[1].second, rep.second_slow_pole_scores[2].second);
  EXPECT_NEAR(rep.second_slow_pole_gain.first, second_best - rep.second_slow_pole_scores[0].second, 1e-9);
  EXPECT_LE(rep.second_slow_pole_gain.first, rep.second_slow_pole_gain.second);
  EXPECT_EQ(rep.slow_pole_time_constants_s, std::vector<double>{8.0});
  // The creep's own time constant wins (held-out simulation 89.6 none, 90.9
  // at 2 s, 94.9 at 8 s, 89.6 at 30 s when written).
  EXPECT_NEAR(with.poles[0][0].poles().back().real(), std::exp(-with.sample_time_s / 8.0), 1e-12);
  // Tied (the default) in the tip frame: one fraction for both outputs, near
  // the simulator's 15% extra strain (0.21 when written: the angles are not
  // linear in the strains).
  ASSERT_EQ(rep.slow_pole_fraction.size(), 2u);
  ASSERT_EQ(rep.slow_pole_fraction[0].size(), 1);
  EXPECT_EQ(rep.slow_pole_fraction[0], rep.slow_pole_fraction[1]);
  EXPECT_GT(rep.slow_pole_fraction[0](0), 0.075);
  EXPECT_LT(rep.slow_pole_fraction[0](0), 0.3);
  // The global linear baseline refits the model's structure with the same tie.
  EXPECT_EQ(rep.slow_pole_tie.poles, std::vector<double>{with.poles[0][0].poles().back().real()});
  EXPECT_TRUE(rep.slow_pole_tie.shared);
  EXPECT_EQ(baselineData(with, rep, {train}).slow_mode.poles, rep.slow_pole_tie.poles);
  // Free, the same pole is kept untied.
  o.slow_pole_form = SlowPoleForm::kFree;
  o.slow_pole_count = 1;  // and no second slow pole tried
  IdentifyReport free_rep;
  const DioPwlObfModel free_fit = identifyModel({train}, o, &free_rep);
  EXPECT_EQ(free_fit.poles[0][0].poles().back().real(), rep.slow_pole_tie.poles.front());
  EXPECT_TRUE(free_rep.slow_pole_tie.poles.empty());
  EXPECT_TRUE(free_rep.slow_pole_fraction.empty());
  EXPECT_TRUE(free_rep.second_slow_pole_scores.empty());
  const eval::ValidationResult v0 = eval::validateModel(without, val, {40}), v1 = eval::validateModel(with, val, {40});
  for (std::size_t out = 0; out < v0.outputs.size(); ++out) {
    // 87.9 -> 95.4 and 90.1 -> 97.4 when written (93.9 and 95.1 with free
    // coefficients); 40 steps barely move.
    EXPECT_GT(v1.outputs[out].fit_sim, v0.outputs[out].fit_sim + 1.5) << v0.outputs[out].name;
    EXPECT_GT(v1.outputs[out].fit_k.at(40), v0.outputs[out].fit_k.at(40) - 0.5) << v0.outputs[out].name;
  }
}
