#include "plsa/diagnose/run_data.hpp"
#include "plsa/core/angle_units.hpp"
#include "plsa/core/median.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/sim/sim_config.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace plsa::diagnose {

Eigen::MatrixXd bendingVector(const Eigen::VectorXd& bend_deg, const Eigen::VectorXd& steer_deg) {
  Eigen::MatrixXd v(bend_deg.size(), 2);
  for (Eigen::Index i = 0; i < bend_deg.size(); ++i) {
    const double s = steer_deg(i) * kPi / 180.0;
    v(i, 0) = bend_deg(i) * std::cos(s);
    v(i, 1) = bend_deg(i) * std::sin(s);
  }
  return v;
}

namespace {

// The columns a run reads: each named once, none both an input and an
// output or pressure, three pressures or none; a pressure set half present
// in the log is an error (all absent: a run without pressures).
void checkColumns(const io::Log& log, const RunColumns& c, const std::string& where) {
  if (c.inputs.empty() || c.inputs.size() > 3) throw std::invalid_argument(where + "needs 1 to 3 input columns");
  if (c.outputs.size() != 2) throw std::invalid_argument(where + "needs exactly 2 output columns");
  if (!c.pressures.empty() && c.pressures.size() != 3)
    throw std::invalid_argument(where + "needs 3 pressure columns, one per chamber, or none");
  std::vector<std::string> all = c.inputs;
  all.insert(all.end(), c.outputs.begin(), c.outputs.end());
  all.insert(all.end(), c.pressures.begin(), c.pressures.end());
  for (auto at = all.begin(); at != all.end(); ++at)
    if (std::find(all.begin(), at, *at) != at)
      throw std::invalid_argument(where + "column '" + *at +
                                  "' is named twice among the inputs, outputs and pressures");
  const auto present =
      std::count_if(c.pressures.begin(), c.pressures.end(), [&](const std::string& p) { return log.hasColumn(p); });
  if (present > 0 && present < static_cast<long>(c.pressures.size()))
    for (const auto& p : c.pressures)
      if (!log.hasColumn(p))
        throw std::invalid_argument(where + "has some pressure columns but no '" + p +
                                    "' (name all three, or --pressures none)");
  if (!log.hasColumn(io::standard_columns::kTime))
    throw std::invalid_argument(where + "has no " + io::standard_columns::kTime + " column");
  if (log.samples() < 50)
    throw std::invalid_argument(where + "has " + std::to_string(log.samples()) + " samples; at least 50 needed");
}

Eigen::MatrixXd commandsOf(const io::Log& log, const RunColumns& c, double max_pressure_bar, const std::string& where) {
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(log.samples(), 3);
  for (std::size_t j = 0; j < c.inputs.size(); ++j)
    u.col(static_cast<Eigen::Index>(j)) = log.column(c.inputs[j]) * c.input_scale;
  for (Eigen::Index i = 0; i < u.rows(); ++i)
    for (Eigen::Index j = 0; j < 3; ++j) {
      const double v = u(i, j);
      if (!std::isfinite(v))
        throw std::invalid_argument(where + "input " + std::to_string(j + 1) + " is not finite at row " +
                                    std::to_string(i + 1));
      if (v < -1e-9 || v > max_pressure_bar * 1.5 + 1e-9)
        throw std::invalid_argument(where + "input " + std::to_string(j + 1) + " = " + significantDigits(v, 6) +
                                    " bar at row " + std::to_string(i + 1) + " is outside 0.." +
                                    significantDigits(max_pressure_bar, 6) + " bar (check --input-scale)");
    }
  return u.cwiseMax(0.0);
}

bool hasPressures(const io::Log& log, const RunColumns& c) {
  return !c.pressures.empty() && log.hasColumn(c.pressures[0]);  // all or none (checkColumns)
}

// Outputs and pressures: finite, no gross outlier (a glitch would swamp the
// gap every calibration minimises), and outputs that move.
void checkMeasured(const io::Log& log, const RunColumns& c, const std::string& where) {
  std::vector<std::string> measured = c.outputs;
  if (hasPressures(log, c)) measured.insert(measured.end(), c.pressures.begin(), c.pressures.end());
  for (const auto& name : measured)
    if (!log.column(name).allFinite()) throw std::invalid_argument(where + "column '" + name + "' has NaN or Inf");
  const std::string outlier = identify::grossOutlier(log, measured);
  if (!outlier.empty()) throw std::invalid_argument("diagnosis: " + outlier + "; fix or remove the row");
  bool moves = false;
  for (const auto& name : c.outputs) {
    const Eigen::VectorXd y = log.column(name);
    moves = moves || y.maxCoeff() > y.minCoeff();
  }
  if (!moves) throw std::invalid_argument(where + "the outputs never move: there is no response to diagnose");
}

}  // namespace

RunData runFromLog(const io::Log& log, const RunColumns& c, double max_pressure_bar) {
  const std::string where = "diagnosis: run '" + log.source + "': ";
  if (!(c.input_scale > 0) || !std::isfinite(c.input_scale))
    throw std::invalid_argument(where + "input scale must be positive");
  checkColumns(log, c, where);
  RunData r;
  r.name = log.source;
  r.sample_time_s = io::checkedSampleTime(log, io::standard_columns::kTime, io::kToleratedGapFactor);
  if (!(r.sample_time_s > 0)) throw std::invalid_argument(where + "time does not increase");
  const double rate_hz = 1.0 / r.sample_time_s;
  if (!(rate_hz >= sim::kMinSampleRateHz && rate_hz <= sim::kMaxSampleRateHz))
    throw std::invalid_argument(where + "its time column steps every " + significantDigits(r.sample_time_s, 6) +
                                " s (" + significantDigits(rate_hz, 6) + " Hz); the simulator replays runs at " +
                                significantDigits(sim::kMinSampleRateHz, 6) + " to " +
                                significantDigits(sim::kMaxSampleRateHz, 6) + " Hz (is the time column in seconds?)");
  r.commands = commandsOf(log, c, max_pressure_bar, where);
  checkMeasured(log, c, where);
  const Eigen::MatrixXd y = log.columnsOf(c.outputs);
  r.outputs = c.map == OutputMap::kAngles ? bendingVector(y.col(0), y.col(1)) : y;
  if (hasPressures(log, c)) r.pressures = log.columnsOf(c.pressures);
  r.start = c.start == RunStart::kAuto ? detectRunStart(r, c.map) : c.start;
  return r;
}

RunStart detectRunStart(const RunData& run, OutputMap map) {
  if (run.samples() == 0) return RunStart::kAtRest;
  const double first = run.commands.row(0).maxCoeff();
  if (first < 0.005) return RunStart::kAtRest;
  if (run.hasPressures()) {
    // The first sample is taken after a first period of filling: a chamber
    // filling from vent is already part way (a third within one time
    // constant), so only a pressure close to its command means settled.
    Eigen::Index c = 0;
    run.commands.row(0).maxCoeff(&c);
    return std::abs(run.pressures(0, c) - first) <= 0.2 * first ? RunStart::kSettled : RunStart::kAtRest;
  }
  if (map != OutputMap::kAngles) return RunStart::kAtRest;
  std::vector<double> lengths(static_cast<std::size_t>(run.samples()));
  for (Eigen::Index i = 0; i < run.samples(); ++i) lengths[static_cast<std::size_t>(i)] = run.outputs.row(i).norm();
  return run.outputs.row(0).norm() < 0.15 * median(std::move(lengths)) ? RunStart::kAtRest : RunStart::kSettled;
}

std::pair<RunData, RunData> splitByTime(const RunData& run, double heldout_fraction) {
  if (!(heldout_fraction > 0 && heldout_fraction < 1))
    throw std::invalid_argument("held-out fraction must be in (0, 1)");
  const Eigen::Index n = run.samples();
  const auto cut = static_cast<Eigen::Index>(std::lround(n * (1.0 - heldout_fraction)));
  if (cut < 50 || n - cut < 50) throw std::invalid_argument("diagnosis: run '" + run.name + "' is too short to split");
  auto part = [&](Eigen::Index from, Eigen::Index len, const std::string& tag) {
    RunData r;
    r.name = run.name + tag;
    r.sample_time_s = run.sample_time_s;
    r.commands = run.commands.middleRows(from, len);
    r.outputs = run.outputs.middleRows(from, len);
    if (run.hasPressures()) r.pressures = run.pressures.middleRows(from, len);
    // The held-out part starts wherever the run was: the simulator gets
    // there by replaying the run's start and what came before (a fresh start
    // there lost the run's hysteresis, creep and drift: a probe's single run
    // from the very simulator was a 39% gap against a 0.8% noise floor).
    r.start = run.start;
    r.lead_in = run.commands.topRows(from);
    return r;
  };
  return {part(0, cut, " (training part)"), part(cut, n - cut, " (held-out part)")};
}

}  // namespace plsa::diagnose
