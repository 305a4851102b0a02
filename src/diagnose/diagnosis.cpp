#include "plsa/diagnose/diagnosis.hpp"
#include "plsa/core/number_text.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <map>
#include <stdexcept>
#include <utility>

#include "calibration_starts.hpp"
#include "verdict.hpp"
#include "plsa/core/parallel_for.hpp"

namespace plsa::diagnose {
namespace {

void say(const DiagnoseOptions& o, const std::string& line) {
  if (o.log) o.log(line);
}

// A note (none when empty) kept in the diagnosis and logged.
void addNote(const DiagnoseOptions& o, Diagnosis& d, const std::string& note) {
  if (note.empty()) return;
  d.notes.push_back(note);
  say(o, "plsa diagnose: note: " + note);
}

struct Residuals {
  std::vector<Eigen::MatrixXd> residual, sim;
};

Residuals residualsOf(const sim::SimConfig& c, const std::vector<RunData>& runs, const OutputFit& fit, OutputMap map) {
  Residuals r;
  for (const auto& run : runs) {
    const SimTrace t = simulateRun(c, run, map);
    const Eigen::MatrixXd yhat = map == OutputMap::kAffine ? fit.apply(t.outputs) : t.outputs;
    r.residual.push_back(run.outputs - yhat);
    r.sim.push_back(t.outputs);
  }
  return r;
}

Breakdown breakdownFor(const sim::SimConfig& c, const std::vector<RunData>& runs, const OutputFit& fit, OutputMap map) {
  const Residuals r = residualsOf(c, runs, fit, map);
  BreakdownInputs in;
  in.runs = &runs;
  in.residuals = &r.residual;
  in.sim_outputs = &r.sim;
  in.map = map;
  in.bend_direction_deg = c.geometry.bend_direction_deg;
  in.max_pressure_bar = c.max_pressure_bar;
  return breakdownGap(in);
}

// The candidates asked for, or every effect the simulator has off; each known, off and named once.
std::vector<std::string> checkedCandidates(const sim::SimConfig& simulator, const DiagnoseOptions& o) {
  std::vector<std::string> candidates = o.candidates;
  if (candidates.empty())
    for (const auto& e : sim::effectNames())
      if (!simulator.effectEnabled(e)) candidates.push_back(e);
  for (const auto& e : candidates) {
    if (std::find(sim::effectNames().begin(), sim::effectNames().end(), e) == sim::effectNames().end())
      throw std::invalid_argument("diagnose: unknown candidate effect '" + e + "'");
    if (simulator.effectEnabled(e))
      throw std::invalid_argument("diagnose: candidate '" + e + "' is already switched on in the simulator");
    if (std::count(candidates.begin(), candidates.end(), e) > 1)
      throw std::invalid_argument("diagnose: candidate '" + e + "' is named twice (each is tried once)");
  }
  return candidates;
}

// The runs calibration trains on and the runs every gap is scored on: one
// run split in time, else the last third of the runs (at least one) held out.
struct RunSplit {
  std::vector<RunData> train, held;
};

RunSplit splitRuns(const std::vector<RunData>& runs, const DiagnoseOptions& o) {
  RunSplit s;
  if (runs.size() == 1) {
    auto [a, b] = splitByTime(runs[0], o.heldout_fraction);
    s.train.push_back(a);
    s.held.push_back(b);
  } else {
    const std::size_t n_held = std::max<std::size_t>(1, runs.size() / 3);
    s.train.assign(runs.begin(), runs.end() - static_cast<std::ptrdiff_t>(n_held));
    s.held.assign(runs.end() - static_cast<std::ptrdiff_t>(n_held), runs.end());
  }
  return s;
}

// The simulator as calibrated so far: its configuration, held-out and
// training gaps, the output fit the held-out gap used, and where that gap lies.
struct CalibratedState {
  sim::SimConfig config;
  Gap heldout, train;
  OutputFit fit;
  Breakdown where;
  std::vector<std::string> held;  ///< parameters its calibrations hold (a kept effect's part left out)
  std::vector<std::pair<std::string, double>> values;  ///< its calibrated parameters
};

// What every stage of the forward selection reads.
struct SelectionContext {
  const RunSplit& runs;
  const DiagnoseOptions& o;
  OutputMap map;
  double step_s = 0.0;   ///< the internal step calibrations run at (0: as configured)
  FillLawEstimate fill;  ///< the chambers' fill law from the training runs' logged pressures
};

// A calibration at the selection's internal step; the result carries the
// configured step again, with its training gap and output map measured there.
CalibrationResult calibrateAtStep(const sim::SimConfig& start, const std::vector<std::string>& modules,
                                  const SelectionContext& x, const CalibrationOptions& o) {
  if (!(x.step_s > start.internal_step_s)) return calibrate(start, modules, x.runs.train, o);
  CalibrationResult r = calibrateCoarse(start, x.step_s, modules, x.runs.train, o);
  r.train_gap = measureGap(r.config, x.runs.train, o.gap, &r.fit);
  return r;
}

// The coarser calibration step: `calibration_step_s`, else half of it (while
// above the configured step), the first that moves the calibrated training
// gap by at most the tolerance; 0 when neither does. `tried`: each step tried,
// coarsest first, and how far it moved the gap (points).
double calibrationStep(const sim::SimConfig& calibrated, const Gap& train, const SelectionContext& x, const Gap& noise,
                       std::vector<std::pair<double, double>>& tried) {
  const DiagnoseOptions& o = x.o;
  for (double step : {o.calibration_step_s, o.calibration_step_s / 2.0}) {
    if (!(step > calibrated.internal_step_s)) break;
    const sim::SimConfig coarse = atLeastStep(calibrated, step, o.calibration.coarse_integrator);
    const double moved = std::abs(measureGap(coarse, x.runs.train, o.calibration.gap).percent() - train.percent());
    tried.emplace_back(step, moved);
    if (moved <= o.coarse_step_tolerance * noise.percent()) return step;
  }
  return 0.0;
}

// The progress line naming the calibrations' step and why.
std::string calibrationStepLine(const Diagnosis& d, const DiagnoseOptions& o, double sample_time_s) {
  std::string s = "plsa diagnose: candidates calibrated at a " + significantDigits(1e3 * d.calibration_step_s, 3) +
                  " ms internal step";
  // As the simulator takes it: a whole number of steps a sample.
  const double per_sample = std::max(1.0, std::round(sample_time_s / d.calibration_step_s)),
               taken = sample_time_s / per_sample;
  if (std::abs(taken - d.calibration_step_s) > 1e-9)
    s += ", " + significantDigits(1e3 * taken, 3) + " ms at the runs' " + significantDigits(1.0 / sample_time_s, 3) +
         " Hz (" + significantDigits(per_sample, 3) + " a sample)";
  s += ", by the " + d.calibration_integrator + " integrator";
  if (d.calibration_step_trials.empty()) return s;
  s += " (on the calibrated nominal physics";
  for (const auto& [step, moved] : d.calibration_step_trials)
    s += ", " + significantDigits(1e3 * step, 3) + " ms moves the training gap by " + significantDigits(moved, 2) +
         " points";
  return s + "; the tolerance " + significantDigits(o.coarse_step_tolerance * d.noise.percent(), 2) + ", " +
         significantDigits(o.coarse_step_tolerance, 3) +
         " noise floors; every gap is measured at the configured step and integrator)";
}

// Calibration modules: the nominal physics, the kept effects, then `extra` if given.
std::vector<std::string> modulesWith(const std::vector<std::string>& selected, const std::string& extra = "") {
  std::vector<std::string> modules = {"nominal"};
  modules.insert(modules.end(), selected.begin(), selected.end());
  if (!extra.empty()) modules.push_back(extra);
  return modules;
}

// The simulator's chambers as a fill law: the start of the fit to the
// logged pressures.
FillLaw chambersOf(const sim::SimConfig& c) {
  FillLaw law;
  law.fill_time_constant_s = law.vent_time_constant_s = c.pneumatics.time_constant_s;
  law.max_rate_bar_per_s = c.pneumatics.max_rate_bar_per_s;
  return law;
}

// Noise floor, the simulator as given, then the
// nominal calibration: the baseline every candidate is measured against.
CalibratedState calibrateBaseline(const sim::SimConfig& simulator, const SelectionContext& x, Diagnosis& d) {
  const DiagnoseOptions& o = x.o;
  const GapOptions& g = o.calibration.gap;
  const RunSplit& r = x.runs;
  d.noise = noiseFloor(r.held, g);
  OutputFit raw_fit;
  measureGap(simulator, r.train, g, &raw_fit);
  d.heldout_uncalibrated = measureGap(simulator, r.held, g, &raw_fit, false);
  addNote(o, d, implausibleScaleNote(simulator, r.train, x.map));
  say(o, "plsa diagnose: " + std::to_string(r.train.size()) + " training / " + std::to_string(r.held.size()) +
             " held-out run(s); held-out gap of the simulator as given " + pct(d.heldout_uncalibrated.percent()) +
             ", noise floor " + pct(d.noise.percent()));
  CalibrationOptions nominal_opts = o.calibration;
  nominal_opts.max_evaluations = o.nominal_evaluations;
  nominal_opts.progress = [&](int e, double best) {
    say(o, "  nominal calibration: " + std::to_string(e) + " evaluations, training gap " + pct(100 * std::sqrt(best)));
  };
  const CalibrationResult base = calibrateNominal(simulator, r.train, x.fill, nominal_opts, o, d.nominal_evaluations);
  CalibratedState s{base.config, {}, base.train_gap, base.fit, {}, {}, base.values};
  s.heldout = measureGap(base.config, r.held, g, &s.fit, false);
  s.where = breakdownFor(base.config, r.held, s.fit, x.map);
  d.calibrated = base.config;
  d.nominal_params = base.values;
  d.train_before = base.train_gap;
  d.gap_before = s.heldout;
  d.where = s.where;
  say(o, "plsa diagnose: nominal physics calibrated (" + std::to_string(d.nominal_evaluations) +
             " simulator runs); held-out gap " + pct(d.gap_before.percent()));
  return s;
}

// The bar a candidate must clear: the current model re-calibrated with a
// candidate's budget and nothing added. Without it, any candidate was
// credited with what further optimisation of the kept parameters buys, and
// later rounds kept effects that were not there. It gets the budget of the
// largest candidate, spent as the candidates spend theirs: with screening
// first the runs of the largest screening stage (at its step), then two
// calibrations, the second from where the first ended (in later rounds a
// candidate without a round-1 gain gets one calibration, so against it the
// bar has the larger budget). Returns the model so re-calibrated.
CalibratedState recalibratedWithNothingAdded(const CalibratedState& s, const std::vector<std::string>& selected,
                                             const std::vector<std::string>& remaining, const Screening& screen,
                                             const SelectionContext& x) {
  const DiagnoseOptions& o = x.o;
  const std::vector<std::string> modules = modulesWith(selected);
  sim::SimConfig start = s.config;
  if (screen.evaluations > 0) {
    std::size_t points = 0;
    for (const auto& e : remaining) {
      sim::SimConfig c = s.config;
      enableCandidate(c, e, o);
      points = std::max(points, spreadFor(c, e, x.runs.train, x.fill, x.map).size());
    }
    CalibrationOptions screening = o.calibration;
    screening.max_evaluations = screen.evaluations * static_cast<int>(points);
    screening.evaluations_per_parameter = 0;
    screening.held = s.held;
    const sim::SimConfig screened = calibrateCoarse(s.config, screen.step_s, modules, x.runs.train, screening).config;
    if (measureGap(screened, x.runs.train, o.calibration.gap).total < s.train.total) start = screened;
  }
  CalibrationOptions same = o.calibration;
  same.max_evaluations = candidateBudget(s.config, modules, remaining, o.calibration);
  same.held = s.held;
  CalibrationResult r = calibrateAtStep(start, modules, x, same);
  const CalibrationResult again = calibrateAtStep(r.config, modules, x, same);
  if (again.train_gap.total < r.train_gap.total) r = again;
  CalibratedState bar{r.config, {}, r.train_gap, r.fit, {}, s.held, r.values};
  bar.heldout = measureGap(r.config, x.runs.held, o.calibration.gap, &bar.fit, false);
  return bar;
}

// One candidate added to the current model, calibrated from each of its
// starts (a task each); the best start's result.
struct CandidateTrial {
  CandidateResult result;
  sim::SimConfig config;
  OutputFit fit;
};

struct StartTrial {
  CalibrationResult calibrated;
  int evaluations = 0;  ///< the screening's runs included
  int start = 0;        ///< 0: neutral, 1: the best spread point
};

// Start 0: neutral; start 1: the best spread point (after screening, if any).
StartTrial calibrateFromStart(const CalibratedState& s, const std::vector<std::string>& selected, const std::string& e,
                              int start, const Screening& screen, const SelectionContext& x) {
  const DiagnoseOptions& o = x.o;
  sim::SimConfig c = s.config;
  enableCandidate(c, e, o);
  const std::vector<std::string> modules = modulesWith(selected, e);
  StartTrial t;
  t.start = start;
  CalibrationOptions held = o.calibration;
  held.held = s.held;
  const CalibrationStart from = start == 0
                                    ? CalibrationStart{neutralStart(c, e), s.held}
                                    : bestSpreadStart(c, e, modules, x.runs.train, x.fill, held, screen, t.evaluations);
  held.held = from.held;
  t.calibrated = calibrateAtStep(from.config, modules, x, held);
  t.evaluations += t.calibrated.evaluations;
  return t;
}

// The candidate's result from its starts' calibrations (the first wins a tie).
CandidateTrial candidateTrial(const CalibratedState& s, const std::string& e, int round, std::vector<StartTrial> starts,
                              const SelectionContext& x) {
  const DiagnoseOptions& o = x.o;
  CandidateResult cr;
  std::size_t best = 0;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    ++cr.starts;
    cr.evaluations += starts[i].evaluations;
    cr.train_gap_per_start.push_back(starts[i].calibrated.train_gap.percent());
    if (starts[i].calibrated.train_gap.total < starts[best].calibrated.train_gap.total) best = i;
  }
  CalibrationResult& r = starts[best].calibrated;
  OutputFit f = r.fit;
  cr.effect = e;
  cr.formulation = r.config.formulationOf(e);  // the law it was switched on with; calibration moves values only
  cr.round = round;
  cr.heldout_before = s.heldout;
  cr.heldout_after = measureGap(r.config, x.runs.held, o.calibration.gap, &f, false);
  cr.train_after = r.train_gap;
  cr.shrink_percent = 100.0 * (1.0 - cr.heldout_after.percent() / std::max(1e-12, s.heldout.percent()));
  cr.params = r.values;
  cr.held = r.held;
  cr.best_start = starts[best].start;
  const auto sig = s.where.signatures.find(e);
  if (sig != s.where.signatures.end()) cr.signature = sig->second;
  return {cr, r.config, f};
}

// Every remaining candidate from its starts (both, or the one in `only`),
// and the nothing-added bar: one task per start, so that two cores finish a
// round together (a candidate as one task left a core idle while the
// costliest ran on). The best spread points' starts (screened in round 1:
// the larger tasks) go first. The results are those of the candidates run
// whole.
std::vector<CandidateTrial> tryCandidates(const CalibratedState& s, const std::vector<std::string>& selected,
                                          const std::vector<std::string>& remaining, int round, const Screening& screen,
                                          const std::map<std::string, int>& only, const SelectionContext& x,
                                          CalibratedState& bar) {
  const std::size_t n = remaining.size();
  std::vector<std::pair<std::size_t, int>> tasks;        // (candidate, start)
  std::vector<std::array<int, 2>> task_of(n, {-1, -1});  // [candidate][start]: its task, or -1
  for (int start : {1, 0})
    for (std::size_t i = 0; i < n; ++i) {
      const auto one = only.find(remaining[i]);
      if (one != only.end() && one->second != start) continue;
      task_of[i][static_cast<std::size_t>(start)] = static_cast<int>(tasks.size());
      tasks.emplace_back(i, start);
    }
  std::vector<StartTrial> starts(tasks.size());
  parallelFor(tasks.size() + 1, x.o.threads, [&](std::size_t k) {
    if (k == tasks.size())
      bar = recalibratedWithNothingAdded(s, selected, remaining, screen, x);
    else
      starts[k] = calibrateFromStart(s, selected, remaining[tasks[k].first], tasks[k].second, screen, x);
  });
  std::vector<CandidateTrial> trials;
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<StartTrial> own;  // start 0 first, as a tie keeps it
    for (const int k : task_of[i])
      if (k >= 0) own.push_back(std::move(starts[static_cast<std::size_t>(k)]));
    trials.push_back(candidateTrial(s, remaining[i], round, std::move(own), x));
  }
  return trials;
}

// Later rounds: a candidate whose round-1 calibration ended no lower than
// round 1's bar explained none of the gap alone; it is tried again (an
// effect can show only once another is modelled) from the one start that
// calibrated it best in round 1, instead of both.
std::map<std::string, int> oneStartForThoseWithoutGain(const Diagnosis& d, const DiagnoseOptions& o) {
  std::map<std::string, int> only;
  if (o.both_starts_in_later_rounds) return only;
  for (const CandidateResult& c : d.ranking) {
    if (c.heldout_after.total < d.recalibrated_round1.total || c.starts != 2) continue;
    only[c.effect] = c.best_start;
  }
  return only;
}

// Polish the kept model with the nominal fit's budget (chosen on training
// data): the next round's baseline, so a candidate is never credited with
// what more optimisation alone buys.
void polishKept(CalibratedState& s, const std::vector<std::string>& selected, const SelectionContext& x) {
  CalibrationOptions polish = x.o.calibration;
  polish.max_evaluations = x.o.nominal_evaluations;
  polish.held = s.held;
  const CalibrationResult refit = calibrateAtStep(s.config, modulesWith(selected), x, polish);
  if (!(refit.train_gap.total < s.train.total)) return;
  s.fit = refit.fit;
  s.config = refit.config;
  s.train = refit.train_gap;
  s.heldout = measureGap(refit.config, x.runs.held, x.o.calibration.gap, &s.fit, false);
  s.where = breakdownFor(s.config, x.runs.held, s.fit, x.map);
  s.values = refit.values;
}

// When the selection ends after keeping effects (a later round passed
// nothing, or recalibrateAtLimit), the kept model as the nothing-added bar
// re-calibrated it (a candidate's budget, two calibrations) is the final
// one if that lowered its training gap: the
// polish alone left the kept hysteresis's calibration short on sharp
// Bouc-Wen physics (a self-check case: 11.1% held out against 4.9% after
// the bar's calibration). The last kept step's final gap records it.
void keepRecalibrationAtStop(CalibratedState& s, CalibratedState& recalibrated, const SelectionContext& x,
                             Diagnosis& d) {
  if (d.steps.empty() || !(recalibrated.train.total < s.train.total)) return;
  say(x.o, "plsa diagnose: the kept model re-calibrated with nothing added lowers its training gap " +
               pct(s.train.percent()) + " -> " + pct(recalibrated.train.percent()) + "; held-out gap " +
               pct(s.heldout.percent()) + " -> " + pct(recalibrated.heldout.percent()));
  recalibrated.where = breakdownFor(recalibrated.config, x.runs.held, recalibrated.fit, x.map);
  d.steps.back().heldout_final = recalibrated.heldout;
  addNote(x.o, d, finalRecalibrationNote(d.steps.back(), d.noise, x.o));
  s = std::move(recalibrated);
}

// When the selection ends at its limit (max_selected effects kept, or no
// candidate left) instead of at a round that passes nothing, the kept model
// gets the re-calibration such a round's bar would have given it (a
// candidate's budget for what is left, two calibrations), kept by the same
// rule: the final model does not depend on how the selection ended.
void recalibrateAtLimit(CalibratedState& s, const std::vector<std::string>& selected,
                        const std::vector<std::string>& remaining, const SelectionContext& x, Diagnosis& d) {
  say(x.o, "plsa diagnose: " + std::string(remaining.empty() ? "no candidate left" : "max_selected effects kept") +
               "; re-calibrating the kept model with nothing added");
  CalibratedState recalibrated = recalibratedWithNothingAdded(s, selected, remaining, Screening{0, 0.0}, x);
  keepRecalibrationAtStop(s, recalibrated, x, d);
}

// One round of forward selection: every remaining candidate and the
// nothing-added bar in parallel, ranked by held-out gap; the best is kept
// (moved from `remaining` to `selected`, `s` updated and polished) when it
// beats the bar by the noise margin. Returns whether it was.
bool selectionRound(int round, CalibratedState& s, std::vector<std::string>& selected,
                    std::vector<std::string>& remaining, const SelectionContext& x, Diagnosis& d) {
  const DiagnoseOptions& o = x.o;
  // Screening in the first round only: it finds the basin of the effect
  // that moves the nominal physics most; later rounds start from a model
  // that has absorbed it (and would take twice as long).
  const Screening screen{round == 1 ? o.screen_evaluations : 0, o.screen_step_s};
  CalibratedState recalibrated = s;
  const std::map<std::string, int> only = round == 1 ? std::map<std::string, int>{} : oneStartForThoseWithoutGain(d, o);
  const std::vector<CandidateTrial> trials =
      tryCandidates(s, selected, remaining, round, screen, only, x, recalibrated);
  const Gap null_gap = recalibrated.heldout;
  std::vector<std::size_t> order(trials.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return trials[a].result.heldout_after.total < trials[b].result.heldout_after.total;
  });
  for (std::size_t i : order) {
    const CandidateResult& r = trials[i].result;
    char line[256];
    std::snprintf(line, sizeof line, "  round %d: %-14s held-out gap %s -> %s (shrink %.1f%%)", round, r.effect.c_str(),
                  pct(r.heldout_before.percent()).c_str(), pct(r.heldout_after.percent()).c_str(), r.shrink_percent);
    say(o, line);
    (round == 1 ? d.ranking : d.later_rounds).push_back(r);
  }
  say(o, "  round " + std::to_string(round) + ": re-calibrated with nothing added: held-out gap " +
             pct(s.heldout.percent()) + " -> " + pct(null_gap.percent()));
  const CandidateTrial& best = trials[order[0]];
  const Gap bar = null_gap.total < s.heldout.total ? null_gap : s.heldout;
  if (round == 1) d.recalibrated_round1 = bar;
  const double drop = bar.total - best.result.heldout_after.total;
  if (!clearsMargin(drop, bar, d.noise, o)) {
    say(o, "plsa diagnose: round " + std::to_string(round) + ": the best, " + best.result.effect +
               ", does not beat the noise level by the margin over re-calibrating without it; stopping");
    keepRecalibrationAtStop(s, recalibrated, x, d);
    return false;
  }
  const std::string kept = best.result.effect;
  selected.push_back(kept);
  s = {best.config, best.result.heldout_after, best.result.train_after, best.fit,
       {},          best.result.held,          best.result.params};
  s.where = breakdownFor(s.config, x.runs.held, s.fit, x.map);
  remaining.erase(std::find(remaining.begin(), remaining.end(), kept));
  polishKept(s, selected, x);
  d.steps.push_back({kept, best.result.heldout_after, s.heldout, s.heldout});
  addNote(o, d, polishNote(d.steps.back(), d.noise, o));
  say(o, "plsa diagnose: keeping " + kept + " (calibration polished); held-out gap now " + pct(s.heldout.percent()));
  return true;
}

// The first held-out run as measured, as the nominal calibration simulates
// it and as the final model does.
void traceFirstHeldOutRun(Diagnosis& d, const CalibratedState& before, const CalibratedState& after,
                          const RunData& run) {
  const Residuals b = residualsOf(before.config, {run}, before.fit, d.map);
  const Residuals a = residualsOf(after.config, {run}, after.fit, d.map);
  d.trace_real = run.outputs;
  d.trace_before = run.outputs - b.residual[0];
  d.trace_after = run.outputs - a.residual[0];
  d.trace_dt = run.sample_time_s;
}

// The identified reference, reported and never used to decide, is the
// costliest single stage (identification's structure search, serial): with
// more than one thread it runs on its own while the calibrations do.
std::future<IdentifiedReference> startReference(const RunSplit& r, const DiagnoseOptions& o) {
  const auto policy = o.threads > 1 ? std::launch::async : std::launch::deferred;
  return std::async(policy, [&r] { return identifiedReference(r.train, r.held); });
}

void takeReference(std::future<IdentifiedReference>& pending, const DiagnoseOptions& o, Diagnosis& d) {
  if (!pending.valid()) return;
  d.reference = pending.get();
  say(o, d.reference.available ? "plsa diagnose: an identified model reaches a held-out gap of " +
                                     pct(d.reference.gap.percent()) + " (" + d.reference.note + ")"
                               : "plsa diagnose: no identified reference: " + d.reference.note);
}

}  // namespace

Diagnosis runDiagnosis(const sim::SimConfig& simulator, const std::vector<RunData>& runs, const DiagnoseOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  refuseRepeatedRuns(runs);
  simulator.validate();
  std::vector<std::string> remaining = checkedCandidates(simulator, o);
  if (o.max_selected < 1)
    throw std::invalid_argument("diagnose: max_selected = " + std::to_string(o.max_selected) +
                                ": at least one effect must be allowed");
  if (!o.calibration.held.empty())
    throw std::invalid_argument("diagnose: calibration.held names '" + o.calibration.held.front() +
                                "': the diagnosis's starts choose what their calibrations hold; leave it empty");
  sim::requireIntegratorName(o.calibration.coarse_integrator, "diagnose: calibration.coarse_integrator");
  Diagnosis d;
  d.map = o.calibration.gap.map;
  const RunSplit split = splitRuns(runs, o);
  refuseUnusableSplit(split.train, split.held);
  for (const auto& r : split.train) d.train_runs.push_back(r.name);
  for (const auto& r : split.held) d.heldout_runs.push_back(r.name);
  addNote(o, d, mixedSampleRatesNote(runs));
  SelectionContext x{split, o, d.map, 0.0, {}};
  x.fill = fillLawFromPressures(split.train, chambersOf(simulator), 120, o.threads);
  addNote(o, d, unmodelledPneumaticsNote(x.fill));
  std::future<IdentifiedReference> reference;
  if (o.identified_reference)
    reference = startReference(split, o);
  else
    d.reference.note = "not computed (switched off: --no-identified-reference)";
  const CalibratedState base = calibrateBaseline(simulator, x, d);
  x.step_s = calibrationStep(base.config, base.train, x, d.noise, d.calibration_step_trials);
  d.calibration_step_s = x.step_s > 0.0 ? x.step_s : base.config.internal_step_s;
  d.calibration_integrator = x.step_s > 0.0 ? o.calibration.coarse_integrator : base.config.integrator;
  say(o, calibrationStepLine(d, o, split.train.front().sample_time_s));
  CalibratedState current = base;
  std::vector<std::string> selected;
  bool stopped = false;
  for (int round = 1; !stopped && !remaining.empty() && static_cast<int>(selected.size()) < o.max_selected; ++round)
    stopped = !selectionRound(round, current, selected, remaining, x, d);
  if (!stopped && !selected.empty()) recalibrateAtLimit(current, selected, remaining, x, d);
  takeReference(reference, o, d);
  d.selected = selected;
  d.gap_after = current.heldout;
  d.final_config = current.config;
  d.where_after = selected.empty() ? d.where : current.where;
  d.final_params = current.values;
  judgeConfidence(d, d.recalibrated_round1, o);
  d.verdict = verdictOf(d, o);
  traceFirstHeldOutRun(d, base, current, split.held[0]);
  d.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace plsa::diagnose
