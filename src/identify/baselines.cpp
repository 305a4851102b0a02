#include "plsa/identify/baselines.hpp"

#include <limits>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::identify {

IdentifyOptions paperConfiguration(IdentifyOptions o) {
  o.progress = nullptr;
  o.pole_method = PoleMethod::kFkcm;
  o.local_order = 1;  // the paper's first-order local fits, whatever plsa's model was given
  o.scheduling = SchedulingChoice::kSwitched;
  o.output_frame = OutputFrame::kAsLogged;
  o.play_candidates = {{0.0}};
  o.play_bank_candidates = {};
  o.play_coupling_candidates = {};
  o.play_threshold_candidates = {};
  o.schedule_lag_candidates = {};
  o.slow_pole_candidates = {};
  o.output_drift = OutputDriftChoice::kOff;
  o.second_order_windows_below = -std::numeric_limits<double>::infinity();
  o.score_grid_levels = false;  // the automatic quantile grid: the paper has no such stage
  return o;
}

BaselineData baselineData(const DioPwlObfModel& m, const IdentifyReport& report, const std::vector<io::Log>& logs) {
  BaselineData b;
  std::vector<Eigen::VectorXd> time;
  for (const io::Log& log : logs) {
    b.U.push_back(log.columnsOf(m.inputs));
    b.Y.push_back(log.columnsOf(m.outputs));
    time.push_back(log.column(io::standard_columns::kTime));
  }
  if (report.drift_taken_out) b.Y = removeOutputDrift(b.Y, time, report.output_drift);
  b.slow_mode = report.slow_pole_tie;
  return b;
}

DioPwlObfModel globalLinearOf(const DioPwlObfModel& m, const BaselineData& training) {
  const std::vector<Eigen::MatrixXd>& U = training.U;
  const std::vector<Eigen::MatrixXd>& Y = training.Y;
  DioPwlObfModel g = m;
  // One region: both sides are the same linear model. An input-side model's
  // baseline keeps the side so that it is simulated the same way (from its level).
  const bool input_side = m.schedule_side == ScheduleSide::kInput;
  g.partition = input_side ? PwlPartition::interpolated({}, {}) : PwlPartition::single();
  g.schedule_lag_s = 0.0;
  CoefficientFitOptions fit;
  fit.slow_mode = training.slow_mode;
  fitCoefficients(g, U, Y, fit);
  if (input_side && !m.output_level.empty()) fitOutputLevel(g, U, Y);
  return g;
}

}  // namespace plsa::identify
