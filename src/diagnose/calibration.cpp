#include "plsa/diagnose/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <nlopt.hpp>

#include "plsa/core/median.hpp"
#include "plsa/core/subnormals_flushed.hpp"
#include "plsa/sim/actuator.hpp"

namespace plsa::diagnose {

Eigen::MatrixXd OutputFit::apply(const Eigen::MatrixXd& v) const { return (v * M.topRows<2>()).rowwise() + M.row(2); }

SimTrace replayCommands(const sim::SimConfig& config, const Eigen::MatrixXd& commands, std::uint64_t seed,
                        double preroll_s, Eigen::Index unrecorded, sim::ReadingBranch branch) {
  if (unrecorded < 0 || unrecorded >= commands.rows())
    throw std::invalid_argument("replayCommands: " + std::to_string(unrecorded) + " unrecorded of " +
                                std::to_string(commands.rows()) + " commands");
  // A run's long holds bring the simulator's pressure errors, rates and
  // creep states into the subnormal range; calibrated physics that does so
  // cost 1.8x the CPU time on the real arm (the same diagnosis, 133 against
  // 75 CPU s). Nothing flushed is above 2.2e-308.
  const SubnormalsFlushed flushed;
  sim::Actuator a(config, seed);
  const auto first = std::array<double, 3>{commands(0, 0), commands(0, 1), commands(0, 2)};
  const auto preroll = static_cast<int>(std::lround(preroll_s * config.sample_rate_hz));
  for (int k = 0; k < preroll; ++k) a.stepReading(first, branch);
  a.startRecording();  // the run's lead-in and recorded part are its recording
  for (Eigen::Index i = 0; i < unrecorded; ++i) a.stepReading({commands(i, 0), commands(i, 1), commands(i, 2)}, branch);
  SimTrace t;
  const Eigen::Index n = commands.rows() - unrecorded;
  t.outputs.resize(n, 2);
  t.pressures.resize(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = unrecorded + i;
    const sim::BendingReading r = a.stepReading({commands(k, 0), commands(k, 1), commands(k, 2)}, branch);
    t.outputs.row(i) = r.bending_deg.transpose();
    for (Eigen::Index j = 0; j < 3; ++j) t.pressures(i, j) = r.pressure_bar[static_cast<std::size_t>(j)];
  }
  return t;
}

double settlingTime(const sim::SimConfig& config) {
  constexpr double kBaseS = 3.0, kMostS = 60.0;
  if (!config.creep.enabled) return kBaseS;
  const double slowest = config.creep.time_constant_s * (config.creep.formulation == "two_rate" ? 2.0 : 1.0);
  return std::clamp(5.0 * slowest, kBaseS, kMostS);
}

sim::ReadingBranch readingBranchFor(OutputMap map) {
  return map == OutputMap::kAffine ? sim::ReadingBranch::kUnfolded : sim::ReadingBranch::kSensor;
}

SimTrace simulateRun(const sim::SimConfig& config, const RunData& run, OutputMap map) {
  sim::SimConfig c = config;
  c.sensor.noise_deg = 0.0;
  c.sample_rate_hz = 1.0 / run.sample_time_s;
  // The sample period as validate() computes it (1 / (1 / T) can fall below T by a rounding).
  c.internal_step_s = std::min(c.internal_step_s, 1.0 / c.sample_rate_hz);
  const double preroll = run.start == RunStart::kSettled ? settlingTime(config) : 0.0;
  const sim::ReadingBranch branch = readingBranchFor(map);
  if (run.lead_in.rows() == 0) return replayCommands(c, run.commands, 1, preroll, 0, branch);
  Eigen::MatrixXd all(run.lead_in.rows() + run.commands.rows(), 3);
  all << run.lead_in, run.commands;
  return replayCommands(c, all, 1, preroll, run.lead_in.rows(), branch);
}

namespace {

double spread(const Eigen::MatrixXd& m) {
  if (m.rows() == 0) return 0.0;
  const Eigen::RowVectorXd mean = m.colwise().mean();
  return (m.rowwise() - mean).squaredNorm();
}

// Sums over runs of squared deviation from the pooled mean, and sample count.
double pooledSpread(const std::vector<RunData>& runs, bool pressures) {
  Eigen::Index n = 0;
  for (const auto& r : runs) n += r.samples();
  const Eigen::Index cols = pressures ? 3 : 2;
  Eigen::MatrixXd all(n, cols);
  Eigen::Index at = 0;
  for (const auto& r : runs) {
    all.middleRows(at, r.samples()) = pressures ? r.pressures : r.outputs;
    at += r.samples();
  }
  return spread(all);
}

}  // namespace

Gap measureGap(const sim::SimConfig& config, const std::vector<RunData>& runs, const GapOptions& o, OutputFit* fit,
               bool refit) {
  if (runs.empty()) throw std::invalid_argument("measureGap: no runs");
  const bool pressures = std::all_of(runs.begin(), runs.end(), [](const RunData& r) { return r.hasPressures(); });
  std::vector<SimTrace> traces;
  for (const auto& r : runs) traces.push_back(simulateRun(config, r, o.map));
  OutputFit local;
  OutputFit& f = fit ? *fit : local;
  if (o.map == OutputMap::kAffine && (refit || !fit)) {
    Eigen::Index n = 0;
    for (const auto& r : runs) n += r.samples();
    Eigen::MatrixXd X(n, 3), Y(n, 2);
    Eigen::Index at = 0;
    for (std::size_t k = 0; k < runs.size(); ++k) {
      const auto m = runs[k].samples();
      X.middleRows(at, m) << traces[k].outputs, Eigen::VectorXd::Ones(m);
      Y.middleRows(at, m) = runs[k].outputs;
      at += m;
    }
    f.M = X.colPivHouseholderQr().solve(Y);
  }
  double out_sq = 0.0, p_sq = 0.0;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    const Eigen::MatrixXd yhat = o.map == OutputMap::kAffine ? f.apply(traces[k].outputs) : traces[k].outputs;
    out_sq += (runs[k].outputs - yhat).squaredNorm();
    if (pressures) p_sq += (runs[k].pressures - traces[k].pressures).squaredNorm();
  }
  Gap g;
  g.outputs = out_sq / std::max(1e-12, pooledSpread(runs, false));
  if (pressures) g.pressures = p_sq / std::max(1e-12, pooledSpread(runs, true));
  g.total = g.outputs + o.pressure_weight * g.pressures;
  return g;
}

Gap noiseFloor(const std::vector<RunData>& runs, const GapOptions& o) {
  const bool pressures = std::all_of(runs.begin(), runs.end(), [](const RunData& r) { return r.hasPressures(); });
  auto noiseSq = [](const Eigen::MatrixXd& m) {
    if (m.rows() < 3) return 0.0;
    double sum = 0.0;
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      std::vector<double> d;
      appendAbsSecondDifferences(m.col(c), d);
      const double sigma = whiteNoiseFromSecondDifferences(std::move(d));
      sum += sigma * sigma * static_cast<double>(m.rows());
    }
    return sum;
  };
  double out = 0.0, p = 0.0;
  for (const auto& r : runs) {
    out += noiseSq(r.outputs);
    if (pressures) p += noiseSq(r.pressures);
  }
  Gap g;
  g.outputs = out / std::max(1e-12, pooledSpread(runs, false));
  if (pressures) g.pressures = p / std::max(1e-12, pooledSpread(runs, true));
  g.total = g.outputs + o.pressure_weight * g.pressures;
  return g;
}

double shrinkAboveNoise(const Gap& before, const Gap& after, const Gap& noise) {
  if (!(before.total > 4.0 * noise.total)) return std::numeric_limits<double>::quiet_NaN();
  const double left = std::max(0.0, after.total - noise.total) / (before.total - noise.total);
  return 100.0 * (1.0 - std::sqrt(left));
}

namespace {

// A parameter's normalised coordinate: log scale for wide positive ranges.
struct Axis {
  std::string name;
  double lower, upper;
  bool log;
  double toUnit(double v) const {
    v = std::clamp(v, lower, upper);
    return log ? std::log(v / lower) / std::log(upper / lower) : (v - lower) / (upper - lower);
  }
  double fromUnit(double x) const {
    x = std::clamp(x, 0.0, 1.0);
    return log ? lower * std::pow(upper / lower, x) : lower + x * (upper - lower);
  }
};

// The calibrated parameters of `modules` in `work`: their slots, axes and
// entries in `values` (which gets every parameter, held ones too).
struct Axes {
  std::vector<double*> slots;
  std::vector<Axis> axes;
  std::vector<std::size_t> value_of;
};

Axes calibratedAxes(sim::SimConfig& work, const std::vector<std::string>& modules, const std::vector<std::string>& held,
                    std::vector<std::pair<std::string, double>>& values) {
  Axes a;
  for (const auto& m : modules) {
    if (m != "nominal" && !work.effectEnabled(m))
      throw std::invalid_argument("calibrate: effect '" + m + "' is switched off; switch it on to calibrate it");
    for (const sim::ParamRef& p : work.parameters(m)) {
      const std::string name = m + "." + p.name;
      values.emplace_back(name, *p.value);
      if (std::find(held.begin(), held.end(), name) != held.end()) continue;
      a.slots.push_back(p.value);
      a.axes.push_back({name, p.lower, p.upper, p.lower > 0 && p.upper / p.lower > 20});
      a.value_of.push_back(values.size() - 1);
    }
  }
  for (const auto& h : held)
    if (std::none_of(values.begin(), values.end(), [&](const auto& v) { return v.first == h; }))
      throw std::invalid_argument("calibrate: held parameter '" + h + "' is none of the calibrated modules'");
  return a;
}

}  // namespace

CalibrationResult calibrate(const sim::SimConfig& start, const std::vector<std::string>& modules,
                            const std::vector<RunData>& train, const CalibrationOptions& o) {
  sim::SimConfig work = start;
  CalibrationResult best;
  best.config = start;
  best.held = o.held;
  const Axes calibrated = calibratedAxes(work, modules, o.held, best.values);
  const auto& slots = calibrated.slots;
  const auto& axes = calibrated.axes;
  best.train_gap = measureGap(start, train, o.gap, &best.fit);
  const auto n = static_cast<unsigned>(axes.size());
  if (n == 0) return best;
  std::vector<double> x(n), lo(n, 0.0), hi(n, 1.0);
  for (unsigned i = 0; i < n; ++i) x[i] = axes[i].toUnit(*slots[i]);
  int evaluations = 0;
  auto objective = [&](const std::vector<double>& xs) {
    for (unsigned i = 0; i < n; ++i) *slots[i] = axes[i].fromUnit(xs[i]);
    ++evaluations;
    OutputFit fit;
    Gap g;
    try {
      g = measureGap(work, train, o.gap, &fit);
    } catch (const std::invalid_argument&) {
      return 1e6;  // a combination the simulator rejects: never the answer
    }
    if (!std::isfinite(g.total)) return 1e6;
    if (g.total < best.train_gap.total) {
      best.train_gap = g;
      best.config = work;
      best.fit = fit;
      for (unsigned i = 0; i < n; ++i) best.values[calibrated.value_of[i]].second = *slots[i];
    }
    if (o.progress && evaluations % 25 == 0) o.progress(evaluations, best.train_gap.total);
    return g.total;
  };
  nlopt::opt opt(n >= 2 ? nlopt::LN_BOBYQA : nlopt::LN_COBYLA, n);
  opt.set_lower_bounds(lo);
  opt.set_upper_bounds(hi);
  opt.set_initial_step(std::vector<double>(n, o.initial_step));
  opt.set_maxeval(std::max(o.max_evaluations, o.evaluations_per_parameter * static_cast<int>(n)));
  opt.set_ftol_rel(1e-5);
  using Fn = decltype(objective);
  // nlopt::opt wants a plain function pointer and a context.
  opt.set_min_objective([](unsigned count, const double* xs, double*,
                           void* data) { return (*static_cast<Fn*>(data))(std::vector<double>(xs, xs + count)); },
                        &objective);
  double fmin = 0.0;
  try {
    opt.optimize(x, fmin);
  } catch (const nlopt::roundoff_limited&) {
    // the best point so far stands
  } catch (const std::runtime_error&) {
    // NLopt gave up (e.g. a flat start); the best point so far stands
  }
  best.evaluations = evaluations;
  return best;
}

}  // namespace plsa::diagnose
