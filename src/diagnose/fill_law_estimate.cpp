// The chambers' fill law from logged pressures (fill_law_estimate.hpp).
#include "plsa/diagnose/fill_law_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <stdexcept>

#include <nlopt.hpp>

#include "plsa/core/median.hpp"
#include "plsa/core/parallel_for.hpp"

namespace plsa::diagnose {
namespace {

constexpr double kDriveUnit = 0.1;      ///< bar: the flow law's reference difference
constexpr double kMaxFillStep = 0.005;  ///< s: the longest explicit step (calibrations run at 4 ms where they can)
constexpr int kMinFillSamples = 50;
constexpr Eigen::Index kMaxFillSamples = 4800;  ///< a minute at 80 Hz: the law is well fixed by then

/// One chamber's pressure stepped through a run; returns its squared
/// residual against the logged pressure.
double chamberMisfit(const FillLaw& law, const RunData& run, Eigen::Index c) {
  const double t = run.sample_time_s;
  const int substeps = std::max(1, static_cast<int>(std::ceil(t / kMaxFillStep - 1e-9)));
  const double h = t / substeps;
  const double before = run.start == RunStart::kSettled ? run.commands(0, c) : 0.0;
  const double line_blend = law.line_time_constant_s > 0.0 ? -std::expm1(-h / law.line_time_constant_s) : 0.0;
  double p = run.pressures(0, c), line = before, sum = 0.0;
  for (Eigen::Index i = 0; i + 1 < run.samples(); ++i) {
    for (int s = 0; s < substeps; ++s) {
      // A row's command drives the sample time that ends at the row (the
      // simulator steps, then logs), `delay_s` late.
      const double at = (static_cast<double>(i) * t + (s + 1) * h - law.delay_s) / t;
      const Eigen::Index j = static_cast<Eigen::Index>(std::ceil(at - 1e-9));
      double cmd = j < 0 ? before : run.commands(std::min(j, run.samples() - 1), c);
      if (line_blend > 0.0) cmd = line += (cmd - line) * line_blend;
      const double d = cmd - p;
      if (d == 0.0) continue;
      double tau = d > 0 ? law.fill_time_constant_s : law.vent_time_constant_s;
      if (law.pressure_per_bar != 0.0) tau *= std::exp(law.pressure_per_bar * p);
      const double drive =
          law.exponent == 1.0 ? d : std::copysign(kDriveUnit * std::pow(std::abs(d) / kDriveUnit, law.exponent), d);
      const double step = std::clamp(drive / tau, -law.max_rate_bar_per_s, law.max_rate_bar_per_s) * h;
      p += std::abs(step) < std::abs(d) ? step : d;  // never past the command
    }
    const double e = p - run.pressures(i + 1, c);
    sum += e * e;
  }
  return sum;
}

/// A law's free parameters in [0, 1] each (logarithmic for the time
/// constants and the rate limit), within the simulator's parameter ranges.
struct FillAxis {
  double FillLaw::*field;
  double lower, upper;
  bool log;
  double to01(double v) const {
    v = std::clamp(v, lower, upper);
    return log ? std::log(v / lower) / std::log(upper / lower) : (v - lower) / (upper - lower);
  }
  double from01(double u) const { return log ? lower * std::pow(upper / lower, u) : lower + u * (upper - lower); }
};

const FillAxis kFill{&FillLaw::fill_time_constant_s, 0.005, 2.0, true};
const FillAxis kVent{&FillLaw::vent_time_constant_s, 0.005, 2.0, true};
const FillAxis kExponent{&FillLaw::exponent, 0.3, 1.0, false};
const FillAxis kPerBar{&FillLaw::pressure_per_bar, -4.0, 8.0, false};
const FillAxis kDelay{&FillLaw::delay_s, 0.0, 0.5, false};
const FillAxis kMaxRate{&FillLaw::max_rate_bar_per_s, 0.05, 100.0, true};
const FillAxis kLine{&FillLaw::line_time_constant_s, 0.0, 0.5, false};

struct FillFit {
  FillLaw law;
  double misfit = INFINITY;
};

/// BOBYQA over `axes` from `start`; `tied` keeps the vent time constant at
/// the fill one (the nominal law's single time constant).
FillFit fitAxes(const std::vector<RunData>& runs, const FillLaw& start, const std::vector<FillAxis>& axes, bool tied,
                int evaluations) {
  auto lawAt = [&](const double* u) {
    FillLaw law = start;
    for (std::size_t k = 0; k < axes.size(); ++k) law.*(axes[k].field) = axes[k].from01(u[k]);
    if (tied) law.vent_time_constant_s = law.fill_time_constant_s;
    return law;
  };
  std::function<double(const double*)> objective = [&](const double* u) { return pressureMisfit(lawAt(u), runs); };
  std::vector<double> x(axes.size());
  for (std::size_t k = 0; k < axes.size(); ++k) x[k] = axes[k].to01(start.*(axes[k].field));
  nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(axes.size()));
  opt.set_lower_bounds(std::vector<double>(axes.size(), 0.0));
  opt.set_upper_bounds(std::vector<double>(axes.size(), 1.0));
  opt.set_initial_step(std::vector<double>(axes.size(), 0.1));
  opt.set_maxeval(evaluations);
  opt.set_ftol_rel(1e-6);
  opt.set_min_objective(
      [](unsigned, const double* u, double*, void* f) {
        const double v = (*static_cast<std::function<double(const double*)>*>(f))(u);
        return std::isfinite(v) ? v : 1e30;
      },
      &objective);
  double fmin = objective(x.data());
  try {
    opt.optimize(x, fmin);
  } catch (const nlopt::roundoff_limited&) {
    // The best point seen stands.
  } catch (const std::runtime_error&) {}
  const FillLaw law = lawAt(x.data());
  return {law, pressureMisfit(law, runs)};
}

/// The runs' first kMaxFillSamples samples in all (a run past them cut),
/// with what the fit reads: commands, pressures, sample time and start.
std::vector<RunData> firstMinute(const std::vector<RunData>& runs) {
  std::vector<RunData> head;
  Eigen::Index left = kMaxFillSamples;
  for (const RunData& run : runs) {
    if (left < 2) break;
    const Eigen::Index n = std::min(run.samples(), left);
    RunData r;
    r.name = run.name;
    r.sample_time_s = run.sample_time_s;
    r.start = run.start;
    r.commands = run.commands.topRows(n);
    r.pressures = run.pressures.topRows(n);
    head.push_back(std::move(r));
    left -= n;
  }
  return head;
}

// The pressures' white noise, pooled over runs and chambers.
double pressureNoise(const std::vector<RunData>& runs) {
  std::vector<double> d;
  for (const RunData& run : runs)
    for (Eigen::Index c = 0; c < run.pressures.cols(); ++c) appendAbsSecondDifferences(run.pressures.col(c), d);
  return d.empty() ? 0.0 : whiteNoiseFromSecondDifferences(std::move(d));
}

double pressureSpread(const std::vector<RunData>& runs) {
  double sum = 0.0, sq = 0.0, n = 0.0;
  for (const RunData& run : runs) {
    sum += run.pressures.sum();
    sq += run.pressures.squaredNorm();
    n += static_cast<double>(run.pressures.size());
  }
  return n > 1.0 ? std::sqrt(std::max(0.0, sq / n - (sum / n) * (sum / n))) : 0.0;
}

}  // namespace

std::string unmodelledPneumaticsNote(const FillLawEstimate& e) {
  if (!e.found || !(e.lag_rms_bar > 2.0 * e.noise_bar) || !(e.lag_rms_bar > 0.02 * e.spread_bar)) return "";
  // Held or quantised readings can leave most second differences at zero.
  char noise[96];
  if (e.noise_bar > 1e-6 * e.spread_bar)
    std::snprintf(noise, sizeof noise, "%.3g times their noise (%.2g bar)", e.lag_rms_bar / e.noise_bar, e.noise_bar);
  else
    std::snprintf(noise, sizeof noise, "and they show no measurable noise");
  char text[480];
  std::snprintf(text, sizeof text,
                "the logged pressures follow none of the simulator's fill laws: the best fitted to them alone "
                "leaves %.2g bar RMS, %s: the valves or lines do something no pneumatic-lag candidate models "
                "(quantisation, a regulator's own loop, leakage), and what it leaves no candidate can close",
                e.lag_rms_bar, noise);
  return text;
}

double pressureMisfit(const FillLaw& law, const std::vector<RunData>& runs) {
  double sum = 0.0;
  Eigen::Index n = 0;
  for (const RunData& run : runs) {
    if (!run.hasPressures() || run.samples() < 2) continue;
    for (Eigen::Index c = 0; c < 3; ++c) sum += chamberMisfit(law, run, c);
    n += 3 * (run.samples() - 1);
  }
  return n > 0 ? sum / static_cast<double>(n) : INFINITY;
}

FillLawEstimate fillLawFromPressures(const std::vector<RunData>& all_runs, const FillLaw& start, int evaluations,
                                     int threads) {
  FillLawEstimate e;
  for (const RunData& run : all_runs)
    if (!run.hasPressures() || !(run.sample_time_s > 0)) return e;
  const std::vector<RunData> runs = firstMinute(all_runs);
  Eigen::Index samples = 0;
  for (const RunData& run : runs) samples += run.samples();
  if (samples < kMinFillSamples) return e;
  FillLaw linear = start;
  linear.exponent = 1.0, linear.pressure_per_bar = 0.0, linear.delay_s = 0.0, linear.line_time_constant_s = 0.0;
  const FillFit nominal = fitAxes(runs, linear, {kFill, kMaxRate}, true, evaluations);
  // The full law from the nominal answer and from a pressure-dependent one
  // (a time constant growing with the pressure is a basin of its own), and
  // two volumes in series (a line's lag is one too: from one volume the fit
  // meets it with a delay) with linear flows: the line's time constant
  // trades against the growth and the exponent, so each basin keeps its
  // own axes and the lowest misfit is kept.
  const std::vector<FillAxis> every = {kFill, kVent, kExponent, kPerBar, kDelay, kMaxRate};
  const std::vector<FillAxis> lined = {kFill, kVent, kLine, kDelay, kMaxRate};
  FillLaw growing = nominal.law;
  growing.pressure_per_bar = 3.0;
  growing.fill_time_constant_s = growing.vent_time_constant_s = nominal.law.fill_time_constant_s / 2.0;
  FillLaw two_volumes = nominal.law;  // unequal: at equal times the fit moves both alike
  two_volumes.fill_time_constant_s = two_volumes.vent_time_constant_s = nominal.law.fill_time_constant_s / 3.0;
  two_volumes.line_time_constant_s = nominal.law.fill_time_constant_s * 2.0 / 3.0;
  const FillLaw from[3] = {nominal.law, growing, two_volumes};
  FillFit full[3];
  parallelFor(3, threads,
              [&](std::size_t i) { full[i] = fitAxes(runs, from[i], i < 2 ? every : lined, false, evaluations); });
  const FillFit& lag = *std::min_element(std::begin(full), std::end(full),
                                         [](const FillFit& a, const FillFit& b) { return a.misfit < b.misfit; });
  e.found = std::isfinite(nominal.misfit) && std::isfinite(lag.misfit);
  e.nominal = nominal.law;
  e.lag = lag.misfit <= nominal.misfit ? lag.law : nominal.law;
  e.nominal_rms_bar = std::sqrt(nominal.misfit);
  e.lag_rms_bar = std::sqrt(std::min(lag.misfit, nominal.misfit));
  e.noise_bar = pressureNoise(runs);
  e.spread_bar = pressureSpread(runs);
  return e;
}

}  // namespace plsa::diagnose
