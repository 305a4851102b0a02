#include "identified_models.hpp"

#include <cstdio>

#include "plsa/identify/baselines.hpp"
#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/sim/experiment.hpp"

namespace plsa::bench {
using namespace plsa::identify;  // this command drives identification
namespace {

io::Log run(const sim::Experiment& e, std::uint64_t seed) {
  sim::Actuator rig(sim::SimConfig{}, seed);
  return sim::runExperiment(rig, e);
}

// The same structure with one thing changed, its coefficients fitted again.
DioPwlObfModel refit(DioPwlObfModel m, const io::Log& train) {
  m.output_level.clear();  // a level of the old structure would be wrong for the new
  m.training_drift_per_s.clear();
  fitCoefficients(m, {train.columnsOf(m.inputs)}, {train.columnsOf(m.outputs)});
  return m;
}

DioPwlObfModel withoutSlowPole(DioPwlObfModel m) {
  for (auto& row : m.poles)
    for (auto& ps : row) {
      std::vector<double> kept;
      for (const auto& p : ps.poles())
        if (p.real() < 0.99) kept.push_back(p.real());
      ps = PoleSet::real(kept);
    }
  return m;
}

}  // namespace

std::string describe(const DioPwlObfModel& m) {
  char b[256];
  const bool slow = m.poles[0][0].poles().back().real() > 0.99;
  std::string grid;
  for (const auto& levels : m.partition.breakpoints())
    grid += (grid.empty() ? "" : "x") + std::to_string(levels.size());
  std::snprintf(b, sizeof b, "%d in, %s side %s%s, lag %g s, %d poles%s, %s", m.inputCount(),
                m.schedule_side == ScheduleSide::kInput ? "input" : "output", grid.empty() ? "1" : grid.c_str(),
                m.partition.scheduling() == Scheduling::kSwitched ? " switched" : "", m.schedule_lag_s,
                m.poles[0][0].size(), slow ? " (slow)" : "",
                m.output_frame == OutputFrame::kTipCartesian ? "tip frame" : "angles");
  return b;
}

io::Log drivingRun(std::uint64_t seed) {
  sim::ExperimentOptions eo;
  eo.seed = seed + 1;
  eo.joystick_duration_s = 120;
  return run(sim::joystickExperiment(eo), seed + 100);
}

std::vector<BenchModel> identifiedModels(std::uint64_t seed, void (*say)(const std::string&)) {
  sim::ExperimentOptions eo;
  eo.seed = seed + 1;
  const io::Log grid = run(sim::gridExperiment(eo), seed);
  const io::Log stairs = run(sim::staircaseExperiment(eo), seed);
  std::vector<BenchModel> out;
  auto add = [&](const std::string& name, DioPwlObfModel m) {
    out.push_back({name, describe(m), std::move(m)});
    say("  " + name + ": " + out.back().structure);
  };
  say("identifying the models to measure (the demo's options on the simulator's grid run)");
  IdentifyOptions demo;
  demo.output_frame = OutputFrame::kTipCartesian;
  demo.scheduling = SchedulingChoice::kInputSide;
  demo.output_drift = OutputDriftChoice::kAuto;  // the simulated sensor drifts, as the demo asks
  const DioPwlObfModel model = identifyModel({grid}, demo);
  add("demo", model);
  DioPwlObfModel no_lag = model;
  no_lag.schedule_lag_s = 0.0;
  add("demo, no lag", refit(no_lag, grid));
  add("demo, no slow pole", refit(withoutSlowPole(model), grid));
  DioPwlObfModel angles = model;
  angles.output_frame = OutputFrame::kAsLogged;
  add("demo, angles", refit(angles, grid));
  DioPwlObfModel output_side = model;
  output_side.schedule_side = ScheduleSide::kOutput;
  add("demo, output side", refit(output_side, grid));
  IdentifyOptions two = demo;
  two.inputs = {io::standard_columns::pressure(1), io::standard_columns::pressure(2)};
  add("2 chambers", identifyModel({grid}, two));
  IdentifyOptions one = demo;  // one chamber bends the segment in one plane: no steering to predict
  one.inputs = {io::standard_columns::pressure(1)};
  one.outputs = {io::standard_columns::kBend};
  one.output_frame = OutputFrame::kAsLogged;
  add("1 chamber", identifyModel({stairs}, one));
  // The paper's structure: switched, no play, no lag, angles as logged.
  const IdentifyOptions defaults;
  add("paper's structure", identifyModel({grid}, paperConfiguration(defaults)));
  return out;
}

}  // namespace plsa::bench
