// Fixtures shared by the identification tests, one file per unit
// (test_pwl_partition, test_coefficient_fit, test_model_file,
// test_model_values, test_output_drift, test_validation, test_identify): a
// model with known coefficients, the simulator's runs, and checks.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include <nlohmann/json.hpp>

#include "plsa/dio/dio_transform.hpp"
#include "plsa/eval/model_regressors.hpp"
#include "plsa/eval/arx.hpp"
#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/local_fit.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/identify/output_frame_choice.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/identify/pole_clustering.hpp"
#include "plsa/identify/segmentation.hpp"
#include "plsa/eval/validation.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/obf/decay_rate.hpp"
#include "plsa/sim/actuator.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/testing/alloc_guard.hpp"

namespace plsa::test_fixtures {
using namespace plsa::identify;

template <class F>
inline void expectThrowContaining(F f, const std::string& words) {
  try {
    f();
    ADD_FAILURE() << "accepted; expected an error containing '" << words << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
  }
}

// A DIO-PWL-OBF system with known coefficients, driven by a random staircase.
inline DioPwlObfModel knownModel() {
  DioPwlObfModel m;
  m.inputs = {"u"};
  m.outputs = {"y"};
  m.poles = {{PoleSet::real({0.9, 0.7})}};
  m.shaping.play = {{0.0}};
  m.partition = PwlPartition({0}, {{0.5}});
  Eigen::VectorXd lo(2), hi(2);
  lo << 1.0, -0.3;
  hi << 2.5, 0.4;
  m.coefficients = {{lo}, {hi}};
  m.region_fits = {RegionFit{}, RegionFit{}};
  return m;
}

// Grid training and joystick validation with only the sensor's yaw drifting
// (no tilt) at `yaw_rate` deg/s, and the structure fixed so that only the
// drift stage chooses.
struct DriftRuns {
  io::Log train, val;
};
inline DriftRuns yawDriftRuns(double yaw_rate) {
  sim::SimConfig c;
  for (const auto& e : sim::effectNames()) c.setEffectEnabled(e, false);
  c.setEffectEnabled("sensor_bias", yaw_rate != 0.0);
  c.sensor_bias.tilt_deg = 0.0;
  c.sensor_bias.yaw_drift_deg_per_s = yaw_rate;
  sim::ExperimentOptions eo;
  eo.seed = 2;
  sim::Actuator a(c, 1), b(c, 2);
  return {sim::runExperiment(a, sim::gridExperiment(eo)), sim::runExperiment(b, sim::joystickExperiment(eo))};
}
inline IdentifyOptions fixedInputSide(OutputFrame frame) {
  IdentifyOptions o;
  o.output_frame = frame;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{0.0}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {0.8};
  o.play_threshold_candidates = {};
  o.slow_pole_candidates = {};
  o.output_drift = OutputDriftChoice::kAuto;  // the drift stage runs (and, on these runs, decides)
  return o;
}

// The demo's runs, seed 1: grid training and joystick validation, all effects on.
struct AllEffectsRuns {
  io::Log train, val;
};
inline const AllEffectsRuns& allEffectsRuns() {
  static const AllEffectsRuns runs = [] {
    sim::ExperimentOptions eo;
    eo.seed = 2;
    sim::Actuator a(sim::SimConfig{}, 1), b(sim::SimConfig{}, 101);
    return AllEffectsRuns{sim::runExperiment(a, sim::gridExperiment(eo)),
                          sim::runExperiment(b, sim::joystickExperiment(eo))};
  }();
  return runs;
}

// Every output of `v` above the floors (40-step, 80-step, simulation) and
// above `w` at 40 and 80 steps by the gains.
inline void expectLifted(const eval::ValidationResult& v, const eval::ValidationResult& w,
                         const std::array<double, 3>& floor, const std::array<double, 2>& gain) {
  ASSERT_EQ(v.outputs.size(), w.outputs.size());
  for (std::size_t i = 0; i < v.outputs.size(); ++i) {
    const eval::OutputValidation &t = v.outputs[i], &b = w.outputs[i];
    EXPECT_GT(t.fit_k.at(40), floor[0]) << t.name;
    EXPECT_GT(t.fit_k.at(80), floor[1]) << t.name;
    EXPECT_GT(t.fit_sim, floor[2]) << t.name;
    EXPECT_GT(t.fit_k.at(40), b.fit_k.at(40) + gain[0]) << t.name;
    EXPECT_GT(t.fit_k.at(80), b.fit_k.at(80) + gain[1]) << t.name;
  }
}

}  // namespace plsa::test_fixtures
