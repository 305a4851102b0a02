// Tied slow poles: the coefficient fit with the slow poles' coefficients
// tied to the rest (slow_mode_tie.hpp), its fractions fitted on the
// increments by variable projection and then on the simulated level
// (slow_fraction_levels.hpp).
#include <cmath>
#include <limits>

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

// From the increments' fractions, steps on the training records' simulated
// level, the coefficients solved again after each; the fractions whose
// simulated level fits the records best are kept (the increments' own when
// no step improves on them). Leaves tie.fast and `report` solved at them.
SlowFractions fractionsOnLevels(TiedSlowMode& tie, const DioPwlObfModel& structure, const CoefficientSums::Group& total,
                                SlowFractions alpha, const CoefficientFitOptions& o, const LevelRecords& records,
                                CoefficientFitReport& report) {
  struct Kept {
    SlowFractions alpha;
    DioPwlObfModel fast;
    CoefficientFitReport report;
    double misfit;
  } best{alpha, tie.fast, report, std::numeric_limits<double>::infinity()};
  for (int round = 0; round < kLevelRounds; ++round) {
    const LevelFractionStep step = levelFractionStep(tie, structure, alpha, records, o.slow_mode.shared);
    if (!(step.misfit < best.misfit)) break;
    best = {alpha, tie.fast, report, step.misfit};
    if (round + 1 == kLevelRounds || slowFractionSettled(alpha, step.alpha)) break;
    alpha = step.alpha;
    solveAt(tie, total, alpha, o, report);
  }
  tie.fast = std::move(best.fast);
  report = std::move(best.report);
  return best.alpha;
}

}  // namespace

CoefficientFitReport solveTied(DioPwlObfModel& model, const CoefficientSums::Group& total,
                               const CoefficientFitOptions& o, const LevelRecords* levels) {
  TiedSlowMode tie = tiedSlowMode(model, o.slow_mode.poles);
  CoefficientFitReport report;
  SlowFractions alpha = fractionsOnIncrements(tie, total, o, report);
  if (levels && o.slow_mode.fractions_on_levels)
    alpha = fractionsOnLevels(tie, model, total, std::move(alpha), o, *levels, report);
  model.output_level.clear();
  model.region_fits = tie.fast.region_fits;
  model.coefficients = tie.fast.coefficients;
  for (std::size_t out = 0; out < alpha.size(); ++out) {
    const Eigen::MatrixXd M = tie.blocks[out].at(alpha[out]);
    for (auto& region : model.coefficients) region[out] = M * region[out];
  }
  report.slow_fraction = alpha;
  return report;
}

}  // namespace plsa::identify
