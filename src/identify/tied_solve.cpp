// Tied slow poles: the coefficient fit with the slow poles' coefficients
// tied to the rest (slow_mode_tie.hpp), its fractions fitted on the
// increments by variable projection and then on the simulated level
// (slow_fraction_levels.hpp).
#include <cmath>
#include <limits>

#include "plsa/core/check.hpp"
#include "plsa/identify/slow_fraction_levels.hpp"
#include "plsa/identify/slow_mode_tie.hpp"
#include "tied_solve.hpp"

namespace plsa::identify {
namespace {

// The tied fit at fractions alpha: the coefficients solved in the
// coordinates of the model without the slow poles (into tie.fast), and the
// data misfit of the coefficients they map to, sum c'Jc - 2 c'Jh over outputs.
double solveAt(TiedSlowMode& tie, const CoefficientSums::Group& total, const SlowFractions& alpha,
               const CoefficientFitOptions& o, CoefficientFitReport& report) {
  CoefficientSums::Group reduced = reducedGroup(tie, total, alpha);
  report = solveGroup(tie.fast, reduced, true, o);
  return tiedMisfit(tie, total, tie.fast, alpha);
}

// Most Gauss-Newton steps a tied fit takes on its fractions.
constexpr int kFractionSteps = 20;

// The fractions by variable projection on the increments: for given
// fractions the coefficients are one least-squares solve (solveAt); the
// fractions start at the blended problem's (fitSlowFraction) and take
// Gauss-Newton steps on the full problem (gaussNewtonFractions), each halved
// up to four times while it raises the misfit. Leaves tie.fast and `report`
// solved at the fractions returned.
SlowFractions fractionsOnIncrements(TiedSlowMode& tie, const CoefficientSums::Group& total,
                                    const CoefficientFitOptions& o, CoefficientFitReport& report) {
  SlowFractions alpha = fitSlowFraction(tie, total, o.slow_mode.shared, o.ridge);
  double misfit = solveAt(tie, total, alpha, o, report);
  for (int step = 0; step < kFractionSteps; ++step) {
    const SlowFractions target = gaussNewtonFractions(tie, total, tie.fast, alpha, o.slow_mode.shared);
    const DioPwlObfModel at_alpha = tie.fast;
    const CoefficientFitReport report_at_alpha = report;
    bool taken = false;
    for (double t = 1.0; t >= 1.0 / 16 && !taken; t /= 2) {
      SlowFractions next = alpha;
      for (std::size_t out = 0; out < next.size(); ++out) next[out] += t * (target[out] - alpha[out]);
      const double f = solveAt(tie, total, next, o, report);
      if (f <= misfit + 1e-12 * std::abs(misfit)) {
        taken = true;
        misfit = std::min(misfit, f);
        const bool settled = slowFractionSettled(alpha, next);
        alpha = next;
        if (settled) step = kFractionSteps;
      }
    }
    if (!taken) {  // no step lowers the misfit: the fractions stand
      tie.fast = at_alpha;
      report = report_at_alpha;
      break;
    }
  }
  return alpha;
}

// Rounds of the level step (slow_fraction_levels.hpp), each followed by the
// coefficients' solve at its fractions.
constexpr int kLevelRounds = 3;

// One tied fit through the level rounds: where it is, and the best fractions
// so far with what was solved at them.
struct LevelSearch {
  TiedSlowMode& tie;
  const CoefficientSums::Group& total;
  const SampleWeights& weights;
  CoefficientFitReport& report;
  SlowFractions alpha;
  struct Kept {
    SlowFractions alpha;
    DioPwlObfModel fast;
    CoefficientFitReport report;
    double misfit;
  } best;
  bool done = false;
};

// From the increments' fractions, steps on the training records' simulated
// level, the coefficients solved again after each; the fractions whose
// simulated level fits the records best are kept (the increments' own when
// no step improves on them). Every fit still stepping is simulated in the
// same pass (levelFractionSteps); the last round asks the misfit alone.
// Leaves each tie.fast and report solved at the fractions kept.
void fractionsOnLevels(std::vector<LevelSearch>& fits, const DioPwlObfModel& structure, const CoefficientFitOptions& o,
                       const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& Y) {
  for (int round = 0; round < kLevelRounds; ++round) {
    std::vector<LevelFractionQuery> queries;
    std::vector<LevelSearch*> asked;
    for (LevelSearch& f : fits)
      if (!f.done) {
        queries.push_back({f.tie, f.alpha, f.weights, round + 1 < kLevelRounds});
        asked.push_back(&f);
      }
    if (asked.empty()) break;
    const std::vector<LevelFractionStep> steps = levelFractionSteps(structure, queries, U, Y, o.slow_mode.shared);
    for (std::size_t i = 0; i < asked.size(); ++i) {
      LevelSearch& f = *asked[i];
      f.done = !(steps[i].misfit < f.best.misfit);
      if (f.done) continue;
      f.best = {f.alpha, f.tie.fast, f.report, steps[i].misfit};
      f.done = round + 1 == kLevelRounds || slowFractionSettled(f.alpha, steps[i].alpha);
      if (f.done) continue;
      f.alpha = steps[i].alpha;
      solveAt(f.tie, f.total, f.alpha, o, f.report);
    }
  }
  for (LevelSearch& f : fits) {
    f.tie.fast = std::move(f.best.fast);
    f.report = std::move(f.best.report);
    f.alpha = std::move(f.best.alpha);
  }
}

// The model's coefficients from the tie's fast ones at fractions alpha.
void mapOntoBanks(DioPwlObfModel& model, const TiedSlowMode& tie, const SlowFractions& alpha) {
  model.output_level.clear();
  model.region_fits = tie.fast.region_fits;
  model.coefficients = tie.fast.coefficients;
  for (std::size_t out = 0; out < alpha.size(); ++out) {
    const Eigen::MatrixXd M = tie.blocks[out].at(alpha[out]);
    for (auto& region : model.coefficients) region[out] = M * region[out];
  }
}

}  // namespace

std::vector<CoefficientFitReport> solveTied(std::vector<TiedFit> fits, const CoefficientFitOptions& o,
                                            const std::vector<Eigen::MatrixXd>* U,
                                            const std::vector<Eigen::MatrixXd>* Y) {
  PLSA_CHECK(!fits.empty() && (U == nullptr) == (Y == nullptr), "solveTied: need fits, and both records or neither");
  std::vector<TiedSlowMode> ties;
  std::vector<CoefficientFitReport> reports(fits.size());
  std::vector<SlowFractions> alpha;
  for (std::size_t i = 0; i < fits.size(); ++i) {
    ties.push_back(tiedSlowMode(fits[i].model, o.slow_mode.poles));
    alpha.push_back(fractionsOnIncrements(ties.back(), fits[i].total, o, reports[i]));
  }
  if (U && o.slow_mode.fractions_on_levels) {
    std::vector<LevelSearch> searches;
    for (std::size_t i = 0; i < fits.size(); ++i)
      searches.push_back({ties[i],
                          fits[i].total,
                          fits[i].weights,
                          reports[i],
                          alpha[i],
                          {alpha[i], ties[i].fast, reports[i], std::numeric_limits<double>::infinity()}});
    fractionsOnLevels(searches, fits.front().model, o, *U, *Y);
    for (std::size_t i = 0; i < fits.size(); ++i) alpha[i] = searches[i].alpha;
  }
  for (std::size_t i = 0; i < fits.size(); ++i) {
    mapOntoBanks(fits[i].model, ties[i], alpha[i]);
    reports[i].slow_fraction = alpha[i];
  }
  return reports;
}

}  // namespace plsa::identify
