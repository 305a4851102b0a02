#include "plsa/diagnose/diagnosis.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <mutex>
#include <stdexcept>
#include <thread>

namespace plsa::diagnose {
namespace {

void say(const DiagnoseOptions& o, const std::string& line) {
  if (o.log) o.log(line);
}

std::string pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f%%", v);
  return b;
}

struct Residuals {
  std::vector<Eigen::MatrixXd> residual, sim;
};

Residuals residualsOf(const sim::SimConfig& c, const std::vector<RunData>& runs, const OutputFit& fit, OutputMap map) {
  Residuals r;
  for (const auto& run : runs) {
    const SimTrace t = simulateRun(c, run);
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

// Start values for a newly switched-on effect. Two are calibrated: neutral
// (present but doing nothing, so the fit can only improve on the baseline)
// and the best by training gap of the simulator's own values and two spread
// points (a neutral start alone can sit in a poor basin).
void lagTimesAtNominal(sim::SimConfig& c) {
  c.pneumatic_lag.fill_time_constant_s = c.pneumatic_lag.vent_time_constant_s = c.pneumatics.time_constant_s;
}

void setNeutral(sim::SimConfig& c, const std::string& effect) {
  if (effect == "deadzone") c.deadzone.threshold_bar = 0.0;
  if (effect == "hysteresis") c.hysteresis.width = 0.0;
  if (effect == "stiffening") c.stiffening.per_bar = c.stiffening.per_rad2 = 0.0;
  if (effect == "coupling") c.coupling.per_bar = 0.0;
  if (effect == "pneumatic_lag") {
    lagTimesAtNominal(c);
    c.pneumatic_lag.delay_s = 0.0;
    c.pneumatic_lag.exponent = 1.0;  // a power law is the nominal linear one only at 1
  }
  if (effect == "creep") c.creep.fraction = 0.0;
  if (effect == "sensor_bias") {
    auto& b = c.sensor_bias;
    b.tilt_deg = b.yaw_drift_deg_per_s = b.offset_x_deg = b.offset_y_deg = b.drift_x_deg_per_s = b.drift_y_deg_per_s =
        0.0;
  }
}

// A sensor-bias start read off the residual: per bending-vector component,
// the least-squares offset and drift of (real - simulated) over time.
sim::SimConfig biasFromResidual(sim::SimConfig c, const std::vector<RunData>& train) {
  setNeutral(c, "sensor_bias");
  Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d atb = Eigen::Matrix2d::Zero();  // columns: x, y
  for (const auto& run : train) {
    const SimTrace t = simulateRun(c, run);
    for (Eigen::Index i = 0; i < run.samples(); ++i) {
      const Eigen::Vector2d a(1.0, static_cast<double>(i + 1) * run.sample_time_s);
      ata += a * a.transpose();
      atb += a * (run.outputs.row(i) - t.outputs.row(i));
    }
  }
  const Eigen::Matrix2d sol = ata.ldlt().solve(atb);
  auto& b = c.sensor_bias;
  b.offset_x_deg = std::clamp(sol(0, 0), -10.0, 10.0);
  b.offset_y_deg = std::clamp(sol(0, 1), -10.0, 10.0);
  b.drift_x_deg_per_s = std::clamp(sol(1, 0), -0.2, 0.2);
  b.drift_y_deg_per_s = std::clamp(sol(1, 1), -0.2, 0.2);
  return c;
}

// Spread points for an effect: the simulator's own values and two points
// across each parameter's range; for weighted Prandtl-Ishlinskii hysteresis
// both loop orientations (plays: the output lags; stops: steeper on
// unloading, as elastoplastic or Bouc-Wen laws) with bands closing at zero
// and fixed bands; for sensor bias the residual's offset and drift.
std::vector<sim::SimConfig> spreadFor(const sim::SimConfig& c, const std::string& effect,
                                      const std::vector<RunData>& train) {
  std::vector<sim::SimConfig> spread = {c};
  if (effect == "pneumatic_lag") lagTimesAtNominal(spread[0]);
  for (double u : {0.2, 0.6}) {
    sim::SimConfig trial = c;
    for (const sim::ParamRef& p : trial.parameters(effect)) {
      const bool log = p.lower > 0 && p.upper / p.lower > 20;
      *p.value = log ? p.lower * std::pow(p.upper / p.lower, u) : p.lower + u * (p.upper - p.lower);
    }
    if (effect == "pneumatic_lag") trial.pneumatic_lag.delay_s = u * 0.1;
    spread.push_back(trial);
  }
  if (effect == "hysteresis" && c.hysteresis.formulation == "weighted_pi")
    for (double weight : {-0.4, 0.4})
      for (double fixed : {0.0, 1.0}) {
        sim::SimConfig trial = c;
        auto& h = trial.hysteresis;
        h.weight_narrow = h.weight_mid = h.weight_wide = weight / 3.0;
        h.width = 0.15;
        h.fixed_band_share = fixed;
        spread.push_back(trial);
      }
  if (effect == "sensor_bias") spread.push_back(biasFromResidual(c, train));
  return spread;
}

// Two starts for a candidate's calibration: neutral, and the spread point
// that a short calibration (the screening stage, `screen` simulator runs
// each) takes furthest: ranking the spread points by their raw gap picked
// the wrong basin whenever the effect shifts what the nominal physics must
// do (a stop-type loop moves the static gain). Adds the runs spent to `spent`.
std::vector<sim::SimConfig> startsFor(const sim::SimConfig& c, const std::string& effect,
                                      const std::vector<std::string>& modules, const std::vector<RunData>& train,
                                      const CalibrationOptions& o, int screen, int& spent) {
  sim::SimConfig neutral = c;
  setNeutral(neutral, effect);
  CalibrationOptions quick = o;
  quick.max_evaluations = screen;
  quick.evaluations_per_parameter = 0;
  quick.progress = nullptr;
  double best_gap = INFINITY;
  sim::SimConfig best = c;
  for (const auto& s : spreadFor(c, effect, train)) {
    try {
      if (screen <= 0) {
        const double gap = measureGap(s, train, o.gap).total;
        if (gap < best_gap) best_gap = gap, best = s;
        continue;
      }
      const CalibrationResult r = calibrate(s, modules, train, quick);
      spent += r.evaluations;
      if (r.train_gap.total < best_gap) best_gap = r.train_gap.total, best = r.config;
    } catch (const std::invalid_argument&) {}
  }
  return {neutral, best};
}

// A candidate switched on, with its flexible law unless told otherwise.
void enableCandidate(sim::SimConfig& c, const std::string& effect, const DiagnoseOptions& o) {
  c.setEffectEnabled(effect, true);
  const std::string flexible = sim::flexibleFormulationOf(effect);
  if (o.flexible_laws && !flexible.empty()) c.formulationOf(effect) = flexible;
}

// Runs work(0) .. work(count - 1) on `threads` threads (at least one), each
// index once; rethrows the first exception any of them threw.
void forEachInParallel(std::size_t count, int threads, const std::function<void(std::size_t)>& work) {
  std::vector<std::thread> pool;
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  for (int t = 0; t < std::max(1, threads); ++t)
    pool.emplace_back([&] {
      for (std::size_t i = next++; i < count; i = next++) {
        try {
          work(i);
        } catch (...) {
          std::lock_guard<std::mutex> lock(failure_mutex);
          if (!failure) failure = std::current_exception();
        }
      }
    });
  for (auto& th : pool) th.join();
  if (failure) std::rethrow_exception(failure);
}

// Starts for the nominal fit taken from the data: the static gain scaled by
// regressing the measured bending on the simulated one, then a coarse grid
// of bending frequency, damping and chamber time constant around it, ranked
// by training gap (a local search from the simulator as given stalled in a
// far basin on physics unlike plsa's defaults, and every candidate was then
// credited with what moving the nominal physics bought).
std::vector<sim::SimConfig> nominalStarts(const sim::SimConfig& simulator, const std::vector<RunData>& train,
                                          const GapOptions& g, std::size_t keep, int& spent) {
  sim::SimConfig scaled = simulator;
  double num = 0.0, den = 0.0;
  for (const auto& run : train) {
    const SimTrace t = simulateRun(simulator, run);
    num += (run.outputs.array() * t.outputs.array()).sum();
    den += t.outputs.squaredNorm();
  }
  ++spent;
  if (g.map == OutputMap::kAngles && den > 0 && num > 0) {
    const double k = std::clamp(num / den, 0.2, 5.0);
    scaled.elongation.strain_per_bar = std::clamp(scaled.elongation.strain_per_bar * k, 0.01, 5.0);
    scaled.elongation.quadratic = std::clamp(scaled.elongation.quadratic * k, -5.0, 5.0);
  }
  std::vector<std::pair<double, sim::SimConfig>> ranked;
  for (double f : {0.6, 1.0, 1.6})
    for (double z : {0.35, 0.85, 1.8})
      for (double tc : {0.5, 1.0, 2.5}) {
        sim::SimConfig c = scaled;
        c.bending.natural_freq_hz = std::clamp(c.bending.natural_freq_hz * f, 0.05, 20.0);
        c.bending.damping_ratio = z;
        c.pneumatics.time_constant_s = std::clamp(c.pneumatics.time_constant_s * tc, 0.005, 2.0);
        try {
          ++spent;
          ranked.emplace_back(measureGap(c, train, g).total, c);
        } catch (const std::invalid_argument&) {}
      }
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<sim::SimConfig> starts = {simulator};
  for (std::size_t i = 0; i < ranked.size() && starts.size() < keep + 1; ++i) starts.push_back(ranked[i].second);
  return starts;
}

// The baseline: BOBYQA from the simulator as given and from the best
// data-derived starts (in parallel), then a restart from the best answer
// (a restart shrinks the trust region afresh).
// `spent`: the simulator runs of every stage (the gain regression and grid
// count one per run each).
CalibrationResult calibrateNominal(const sim::SimConfig& simulator, const std::vector<RunData>& train,
                                   const CalibrationOptions& nominal, const DiagnoseOptions& o, int& spent) {
  spent = 0;
  const std::vector<sim::SimConfig> starts = nominalStarts(simulator, train, nominal.gap, 2, spent);
  std::vector<CalibrationResult> results(starts.size());
  CalibrationOptions quiet = nominal;
  quiet.progress = nullptr;
  forEachInParallel(starts.size(), o.threads, [&](std::size_t i) {
    results[i] = calibrate(starts[i], {"nominal"}, train, i == 0 ? nominal : quiet);
  });
  CalibrationResult best = results[0];
  for (const auto& r : results) {
    spent += r.evaluations;
    if (r.train_gap.total < best.train_gap.total) best = r;
  }
  CalibrationResult again = calibrate(best.config, {"nominal"}, train, quiet);
  spent += again.evaluations;
  return again.train_gap.total < best.train_gap.total ? again : best;
}

// The evaluations the largest candidate's calibration may spend.
int candidateBudget(sim::SimConfig c, const std::vector<std::string>& modules,
                    const std::vector<std::string>& candidates, const CalibrationOptions& o) {
  std::size_t base = 0;
  for (const auto& m : modules) base += c.parameters(m).size();
  std::size_t most = 0;
  for (const auto& e : candidates) {
    sim::SimConfig trial = c;
    trial.setEffectEnabled(e, true);
    const std::string flexible = sim::flexibleFormulationOf(e);
    if (!flexible.empty()) trial.formulationOf(e) = flexible;
    most = std::max(most, trial.parameters(e).size());
  }
  return std::max(o.max_evaluations, o.evaluations_per_parameter * static_cast<int>(base + most));
}

// The gap left is over qualified_noise_multiple noise floors. (The
// identified reference is reported beside it, not used to decide: on short
// random excitations its free simulation can be far worse than the
// calibrated simulator, and it would then hide a real shortfall.)
bool farAboveWhatTheDataAllow(const Diagnosis& d, const Gap& left, const DiagnoseOptions& o) {
  return left.percent() > o.qualified_noise_multiple * d.noise.percent();
}

// Round 1's confidence: margins over re-calibration and over the runner-up.
void judgeConfidence(Diagnosis& d, const Gap& bar, const DiagnoseOptions& o) {
  if (d.selected.empty() || d.ranking.empty()) return;
  const double best = d.ranking[0].heldout_after.total;
  const double drop = std::max(1e-12, bar.total - best);
  d.margin_over_recalibration = drop / std::max(1e-12, bar.total);
  d.margin_over_runner_up = 1.0;
  if (d.ranking.size() > 1) {
    d.runner_up = d.ranking[1].effect;
    d.margin_over_runner_up = std::clamp((d.ranking[1].heldout_after.total - best) / drop, 0.0, 1.0);
  }
  if (d.margin_over_runner_up < o.uncertain_margin)
    d.confidence = "uncertain";
  else if (farAboveWhatTheDataAllow(d, d.gap_after, o))
    d.confidence = "qualified";
  else
    d.confidence = "confident";
}

}  // namespace

Diagnosis runDiagnosis(const sim::SimConfig& simulator, const std::vector<RunData>& runs, const DiagnoseOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (runs.empty()) throw std::invalid_argument("diagnose: no real runs given");
  // The same run twice would be held out and trained on: a held-out gap that holds nothing out.
  for (std::size_t i = 0; i < runs.size(); ++i)
    for (std::size_t j = i + 1; j < runs.size(); ++j)
      if (runs[i].samples() == runs[j].samples() && runs[i].commands == runs[j].commands &&
          runs[i].outputs == runs[j].outputs)
        throw std::invalid_argument("diagnose: runs '" + runs[i].name + "' and '" + runs[j].name +
                                    "' hold the same samples; each run may appear once");
  simulator.validate();
  std::vector<std::string> candidates = o.candidates;
  if (candidates.empty())
    for (const auto& e : sim::effectNames())
      if (!simulator.effectEnabled(e)) candidates.push_back(e);
  for (const auto& e : candidates) {
    if (std::find(sim::effectNames().begin(), sim::effectNames().end(), e) == sim::effectNames().end())
      throw std::invalid_argument("diagnose: unknown candidate effect '" + e + "'");
    if (simulator.effectEnabled(e))
      throw std::invalid_argument("diagnose: candidate '" + e + "' is already switched on in the simulator");
  }
  Diagnosis d;
  d.map = o.calibration.gap.map;
  std::vector<RunData> train, held;
  if (runs.size() == 1) {
    auto [a, b] = splitByTime(runs[0], o.heldout_fraction);
    train.push_back(a);
    held.push_back(b);
  } else {
    const std::size_t n_held = std::max<std::size_t>(1, runs.size() / 3);
    train.assign(runs.begin(), runs.end() - static_cast<std::ptrdiff_t>(n_held));
    held.assign(runs.end() - static_cast<std::ptrdiff_t>(n_held), runs.end());
  }
  for (const auto& r : train) d.train_runs.push_back(r.name);
  for (const auto& r : held) d.heldout_runs.push_back(r.name);
  const GapOptions& g = o.calibration.gap;
  d.noise = noiseFloor(held, g);
  OutputFit raw_fit;
  measureGap(simulator, train, g, &raw_fit);
  d.heldout_uncalibrated = measureGap(simulator, held, g, &raw_fit, false);
  say(o, "plsa diagnose: " + std::to_string(train.size()) + " training / " + std::to_string(held.size()) +
             " held-out run(s); held-out gap of the simulator as given " + pct(d.heldout_uncalibrated.percent()) +
             ", noise floor " + pct(d.noise.percent()));

  if (o.identified_reference) {
    d.reference = identifiedReference(train, held);
    say(o, d.reference.available ? "plsa diagnose: an identified model reaches a held-out gap of " +
                                       pct(d.reference.gap.percent()) + " (" + d.reference.note + ")"
                                 : "plsa diagnose: no identified reference: " + d.reference.note);
  }

  // 1. Nominal calibration: the baseline.
  CalibrationOptions nominal_opts = o.calibration;
  nominal_opts.max_evaluations = o.nominal_evaluations;
  nominal_opts.progress = [&](int e, double best) {
    say(o, "  nominal calibration: " + std::to_string(e) + " evaluations, training gap " + pct(100 * std::sqrt(best)));
  };
  const CalibrationResult base = calibrateNominal(simulator, train, nominal_opts, o, d.nominal_evaluations);
  d.calibrated = base.config;
  d.nominal_params = base.values;
  d.train_before = base.train_gap;
  OutputFit fit = base.fit;
  d.gap_before = measureGap(base.config, held, g, &fit, false);
  say(o, "plsa diagnose: nominal physics calibrated (" + std::to_string(d.nominal_evaluations) +
             " simulator runs); held-out gap " + pct(d.gap_before.percent()));
  d.where = breakdownFor(base.config, held, fit, d.map);

  // 2. Candidates, forward selection.
  std::vector<std::string> selected, remaining = candidates;
  sim::SimConfig current = base.config;
  Gap current_gap = d.gap_before;
  Gap current_train = d.train_before;
  Breakdown current_where = d.where;
  OutputFit current_fit = fit;
  for (int round = 1; !remaining.empty() && static_cast<int>(selected.size()) < o.max_selected; ++round) {
    std::vector<CandidateResult> results(remaining.size());
    std::vector<sim::SimConfig> configs(remaining.size());
    std::vector<OutputFit> fits(remaining.size());
    // The bar a candidate must clear: the current model re-calibrated with a
    // candidate's budget and nothing added. Without it, any candidate was
    // credited with what further optimisation of the kept parameters buys,
    // and later rounds kept effects that were not there.
    // It gets the budget of the largest candidate, spent as the candidates
    // spend theirs: two calibrations, the second from where the first ended.
    // Screening in the first round only: it finds the basin of the effect
    // that moves the nominal physics most; later rounds start from a model
    // that has absorbed it (and would take twice as long).
    const int screen = round == 1 ? o.screen_evaluations : 0;
    Gap null_gap = current_gap;
    auto recalibrateAlone = [&] {
      std::vector<std::string> modules = {"nominal"};
      modules.insert(modules.end(), selected.begin(), selected.end());
      CalibrationOptions same = o.calibration;
      same.max_evaluations = candidateBudget(current, modules, remaining, o.calibration);
      CalibrationResult r = calibrate(current, modules, train, same);
      const CalibrationResult again = calibrate(r.config, modules, train, same);
      if (again.train_gap.total < r.train_gap.total) r = again;
      if (screen > 0) {  // ...and the runs of the largest screening stage
        std::size_t points = 0;
        for (const auto& e : remaining) {
          sim::SimConfig c = current;
          enableCandidate(c, e, o);
          points = std::max(points, spreadFor(c, e, train).size());
        }
        same.max_evaluations = screen * static_cast<int>(points);
        same.evaluations_per_parameter = 0;
        const CalibrationResult third = calibrate(r.config, modules, train, same);
        if (third.train_gap.total < r.train_gap.total) r = third;
      }
      OutputFit f = r.fit;
      null_gap = measureGap(r.config, held, g, &f, false);
    };
    auto work = [&](std::size_t i) {
      if (i == remaining.size()) return recalibrateAlone();
      const std::string& e = remaining[i];
      sim::SimConfig c = current;
      enableCandidate(c, e, o);
      std::vector<std::string> modules = {"nominal"};
      modules.insert(modules.end(), selected.begin(), selected.end());
      modules.push_back(e);
      CalibrationResult r;
      CandidateResult cr;
      bool first = true;
      for (const sim::SimConfig& start : startsFor(c, e, modules, train, o.calibration, screen, cr.evaluations)) {
        CalibrationResult trial = calibrate(start, modules, train, o.calibration);
        ++cr.starts;
        cr.evaluations += trial.evaluations;
        cr.train_gap_per_start.push_back(trial.train_gap.percent());
        if (first || trial.train_gap.total < r.train_gap.total) r = std::move(trial);
        first = false;
      }
      OutputFit f = r.fit;
      cr.effect = e;
      cr.formulation = c.formulationOf(e);
      cr.round = round;
      cr.heldout_before = current_gap;
      cr.heldout_after = measureGap(r.config, held, g, &f, false);
      cr.train_after = r.train_gap;
      cr.shrink_percent = 100.0 * (1.0 - cr.heldout_after.percent() / std::max(1e-12, current_gap.percent()));
      cr.params = r.values;
      const auto sig = current_where.signatures.find(e);
      if (sig != current_where.signatures.end()) cr.signature = sig->second;
      results[i] = cr;
      configs[i] = r.config;
      fits[i] = f;
    };
    forEachInParallel(remaining.size() + 1, o.threads, work);  // the last index: the nothing-added bar
    std::vector<std::size_t> order(results.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return results[a].heldout_after.total < results[b].heldout_after.total;
    });
    for (std::size_t i : order) {
      char line[256];
      std::snprintf(line, sizeof line, "  round %d: %-14s held-out gap %s -> %s (shrink %.1f%%)", round,
                    results[i].effect.c_str(), pct(results[i].heldout_before.percent()).c_str(),
                    pct(results[i].heldout_after.percent()).c_str(), results[i].shrink_percent);
      say(o, line);
      (round == 1 ? d.ranking : d.later_rounds).push_back(results[i]);
    }
    say(o, "  round " + std::to_string(round) + ": re-calibrated with nothing added: held-out gap " +
               pct(current_gap.percent()) + " -> " + pct(null_gap.percent()));
    const CandidateResult& best = results[order[0]];
    const Gap bar = null_gap.total < current_gap.total ? null_gap : current_gap;
    if (round == 1) d.recalibrated_round1 = bar;
    const double drop = bar.total - best.heldout_after.total;
    const bool beats_noise = drop > o.margin * d.noise.total && drop > o.min_relative * bar.total;
    if (!beats_noise) {
      say(o, "plsa diagnose: round " + std::to_string(round) + ": the best, " + best.effect +
                 ", does not beat the noise level by the margin over re-calibrating without it; stopping");
      break;
    }
    selected.push_back(best.effect);
    current = configs[order[0]];
    current_gap = best.heldout_after;
    current_train = best.train_after;
    current_fit = fits[order[0]];
    current_where = breakdownFor(current, held, current_fit, d.map);
    d.final_params = best.params;
    remaining.erase(std::find(remaining.begin(), remaining.end(), best.effect));
    {
      // Polish the kept model with the nominal fit's budget (chosen on
      // training data): the next round's baseline, so a candidate is never
      // credited with what more optimisation alone buys.
      std::vector<std::string> modules = {"nominal"};
      modules.insert(modules.end(), selected.begin(), selected.end());
      CalibrationOptions polish = o.calibration;
      polish.max_evaluations = o.nominal_evaluations;
      const CalibrationResult refit = calibrate(current, modules, train, polish);
      if (refit.train_gap.total < current_train.total) {
        OutputFit f = refit.fit;
        current = refit.config;
        current_train = refit.train_gap;
        current_gap = measureGap(refit.config, held, g, &f, false);
        current_fit = f;
        current_where = breakdownFor(current, held, current_fit, d.map);
        d.final_params = refit.values;
      }
    }
    d.steps.push_back({best.effect, current_gap});
    say(o, "plsa diagnose: keeping " + best.effect + " (calibration polished); held-out gap now " +
               pct(current_gap.percent()));
  }
  d.selected = selected;
  d.gap_after = current_gap;
  d.final_config = current;
  d.where_after = selected.empty() ? d.where : current_where;
  if (d.final_params.empty()) d.final_params = d.nominal_params;

  judgeConfidence(d, d.recalibrated_round1, o);
  char v[768];
  if (selected.empty()) {
    std::snprintf(
        v, sizeof v,
        "No candidate effect explains the held-out gap beyond noise: the calibrated simulator's gap is %.1f%% "
        "against a noise floor of %.1f%%, and the best candidate (%s) shrinks it by %.1f%%, less than the "
        "margin.",
        d.gap_before.percent(), d.noise.percent(), d.ranking.empty() ? "none" : d.ranking[0].effect.c_str(),
        d.ranking.empty() ? 0.0 : d.ranking[0].shrink_percent);
  } else {
    std::string list;
    for (const auto& s : selected) list += (list.empty() ? "" : ", then ") + s;
    std::snprintf(v, sizeof v,
                  "The gap is explained by %s: adding %s shrinks the held-out gap from %.1f%% to %.1f%% "
                  "(noise floor %.1f%%).",
                  selected[0].c_str(), list.c_str(), d.gap_before.percent(), d.gap_after.percent(), d.noise.percent());
  }
  d.verdict = v;
  if (d.confidence == "uncertain")
    d.verdict += " Uncertain: " + d.runner_up + " comes within " + pct(100 * d.margin_over_runner_up) + " of " +
                 selected[0] + "'s gain over re-calibrating without either; the data do not separate the two.";
  const std::string reached = d.reference.available && d.reference.gap.percent() < d.gap_after.percent()
                                  ? " and above the " + pct(d.reference.gap.percent()) + " an identified model reaches"
                                  : "";
  if (d.confidence == "qualified")
    d.verdict += " Qualified: the gap left, " + pct(d.gap_after.percent()) + ", is over " +
                 std::to_string(static_cast<int>(o.qualified_noise_multiple)) + " times the noise floor" + reached +
                 ": part of the gap is something no candidate models.";
  if (selected.empty() && farAboveWhatTheDataAllow(d, d.gap_before, o))
    d.verdict += " But the gap, " + pct(d.gap_before.percent()) + ", is over " +
                 std::to_string(static_cast<int>(o.qualified_noise_multiple)) + " times the noise floor" + reached +
                 ": the simulator misses something no candidate models.";

  // Traces of the first held-out run.
  const Residuals before = residualsOf(base.config, {held[0]}, fit, d.map);
  const Residuals after = residualsOf(current, {held[0]}, current_fit, d.map);
  d.trace_real = held[0].outputs;
  d.trace_before = held[0].outputs - before.residual[0];
  d.trace_after = held[0].outputs - after.residual[0];
  d.trace_dt = held[0].sample_time_s;
  d.elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return d;
}

}  // namespace plsa::diagnose
