// Validation of a model on a log: input coverage, sample rate, the tip frame's yaw, departures.
#include <algorithm>
#include <cmath>
#include <random>

#include "plsa/eval/dio_prediction.hpp"
#include "plsa/eval/model_regressors.hpp"
#include "plsa/eval/validation.hpp"
#include "support/hand_built_models.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;

// A tip_cartesian model simulates from its output level, so it carries the
// training run's sensor yaw; a run whose sensor is turned about the segment
// axis must be registered on its first samples (as simulation starts from the
// measured y(0)), turning the steering only: bending, a magnitude, must not move.
TEST(Validation, CountsEachInputAgainstItsOwnTrainingRange) {
  const DriftRuns runs = yawDriftRuns(0.0);
  DioPwlObfModel m = identifyModel({runs.train}, fixedInputSide(OutputFrame::kTipCartesian));
  // The grid moves two chambers over 0.20 to 0.35 bar and leaves the third at zero.
  ASSERT_EQ(m.input_ranges.size(), 3u);
  EXPECT_NEAR(m.input_ranges[0][0], 0.20, 0.005);
  EXPECT_NEAR(m.input_ranges[1][1], 0.35, 0.005);
  EXPECT_NEAR(m.input_ranges[2][1], 0.0, 1e-9);
  EXPECT_EQ(modelFromJson(modelToJson(m)).input_ranges, m.input_ranges);
  // The joystick goes 0.01 bar beyond the grid at either end.
  const Eigen::MatrixXd u = runs.val.columnsOf(m.inputs);
  Eigen::Index below = 0, any = 0;
  for (Eigen::Index k = 0; k < u.rows(); ++k) {
    bool out = false;
    for (Eigen::Index c = 0; c < 3; ++c)
      out = out || u(k, c) < m.input_ranges[static_cast<std::size_t>(c)][0] - 1e-9 ||
            u(k, c) > m.input_ranges[static_cast<std::size_t>(c)][1] + 1e-9;
    any += out;
    below += u(k, 0) < 0.2 - 1e-9 || u(k, 1) < 0.2 - 1e-9;
  }
  ASSERT_GT(below, 0) << "the joystick run never goes below the grid";
  const eval::ValidationResult v = eval::validateModel(m, runs.val, {40});
  EXPECT_DOUBLE_EQ(v.outside_training.any, static_cast<double>(any) / static_cast<double>(u.rows()));
  ASSERT_EQ(v.outside_training.each.size(), 3u);
  EXPECT_GT(v.outside_training.each[0], 0.0);
  EXPECT_GT(v.outside_training.each[1], 0.0);
  EXPECT_EQ(v.outside_training.each[2], 0.0);
  // Against the one range over all inputs ([0, 0.35]: the empty chamber's
  // zero), the excursions below the grid go uncounted: what files from
  // before input_ranges still get.
  m.input_ranges.clear();
  const eval::ValidationResult old = eval::validateModel(m, runs.val, {40});
  EXPECT_LT(old.outside_training.any, v.outside_training.any);
  // A malformed range is rejected by name.
  nlohmann::json j = nlohmann::json::parse(modelToJson(m));
  j["input_ranges"] = {{0.2, 0.35}, {0.2, 0.35}};
  expectThrowContaining([&] { modelFromJson(j.dump()); }, "input_ranges");
  j["input_ranges"] = {{0.2, 0.35}, {0.35, 0.2}, {0.0, 0.0}};
  expectThrowContaining([&] { modelFromJson(j.dump()); }, "input_ranges");
  j["input_ranges"] = {{0.2, 0.35}, {0.2}, {0.0, 0.0}};
  expectThrowContaining([&] { modelFromJson(j.dump()); }, "input_ranges");
  j["input_ranges"] = {{0.2, 0.35}, {"low", 0.35}, {0.0, 0.0}};
  expectThrowContaining([&] { modelFromJson(j.dump()); }, "input_ranges");
}

// A run logged at another rate, with a gap, or scored twice at one horizon is
// named, not scored on the wrong time scale.
TEST(Validation, RejectsAnotherSampleRateAGapAndARepeatedHorizon) {
  const DriftRuns runs = yawDriftRuns(0.0);
  const DioPwlObfModel m = identifyModel({runs.train}, fixedInputSide(OutputFrame::kAsLogged));
  ASSERT_NO_THROW(eval::validateModel(m, runs.val, {40}));
  const int time = runs.val.columnIndex("time_s");
  io::Log faster = runs.val;
  faster.data.col(time) *= 0.8;  // 100 Hz
  expectThrowContaining([&] { eval::validateModel(m, faster, {40}); }, "differs from the model's 0.0125");
  io::Log nearly = runs.val;
  nearly.data.col(time) *= 1.01;  // within the 2% a clock may be off
  EXPECT_NO_THROW(eval::validateModel(m, nearly, {40}));
  io::Log gap = runs.val;
  gap.data.col(time).tail(gap.samples() - 1000).array() += 3 * m.sample_time_s;  // three samples lost
  try {
    eval::validateModel(m, gap, {40});
    ADD_FAILURE() << "accepted a log with three samples lost";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("time gap of 0.05 s before data row 1001"), std::string::npos) << e.what();
  }
  io::Log dropped = runs.val;
  dropped.data.col(time).tail(dropped.samples() - 1000).array() += m.sample_time_s;  // one, as the real arm's logs have
  EXPECT_NO_THROW(eval::validateModel(m, dropped, {40}));
  expectThrowContaining([&] { eval::validateModel(m, runs.val, {40, 80, 40}); }, "horizon 40 is given twice");
}

// A log that starts with the actuator at rest (a user starts recording, then
// moves it): over the registration window the reading's direction is the
// sensor's noise. Registered on it, the whole simulation and every k-step
// prediction turned by whatever that noise pointed at; now the training
// yaw is kept and validation says so, and --settle past the rest registers
// the run's yaw on the bent tip.
TEST(Validation, AStraightTipAtTheStartRegistersNoYaw) {
  const DriftRuns runs = yawDriftRuns(0.0);
  const DioPwlObfModel tip = identifyModel({runs.train}, fixedInputSide(OutputFrame::kTipCartesian));
  const io::Log& val = runs.val;
  const int t = val.columnIndex("time_s"), bend = val.columnIndex("bend_deg"), steer = val.columnIndex("steer_deg");
  const Eigen::Index rest = static_cast<Eigen::Index>(std::llround(6.0 / tip.sample_time_s));
  io::Log rested = val;
  rested.data.resize(rest + val.samples(), val.data.cols());
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (Eigen::Index k = 0; k < rest; ++k) {  // the first sample's inputs, the tip straight
    rested.data.row(k) = val.data.row(0);
    const double x = noise(rng), y = noise(rng);
    rested.data(k, bend) = std::hypot(x, y);
    rested.data(k, steer) = std::atan2(y, x) / kRadPerDeg;
  }
  rested.data.bottomRows(val.samples()) = val.data;
  for (Eigen::Index k = 0; k < rested.samples(); ++k) rested.data(k, t) = static_cast<double>(k) * tip.sample_time_s;
  const double yaw = 3.0;
  rested.data.col(steer).array() += yaw;
  const eval::ValidationResult by_default = eval::validateModel(tip, rested, {40});  // 5 s, 1 deg
  EXPECT_TRUE(by_default.yaw_asked);
  EXPECT_FALSE(by_default.yaw.registered);
  EXPECT_LT(by_default.yaw.bent_share, 0.01);
  EXPECT_EQ(by_default.yaw.offset, 0.0);
  // The steering's simulation, started 5 s later, leaves out a second of the
  // straight tip's noise: named as that, not as a log that does not start at rest.
  const auto steering = std::find_if(by_default.unsettled_starts.begin(), by_default.unsettled_starts.end(),
                                     [](const eval::UnsettledStart& u) { return u.output == "steer_deg"; });
  ASSERT_NE(steering, by_default.unsettled_starts.end());
  EXPECT_NEAR(steering->straight_share, 0.2, 0.01);  // the rest's last second of the 5 s left out
  const std::string said = eval::unsettledStartWarnings({*steering})[0];
  EXPECT_NE(said.find("the tip is straight on 20% of the samples before then"), std::string::npos) << said;
  EXPECT_EQ(said.find("may not start at rest"), std::string::npos) << said;
  // The same as carrying the training yaw, scored on the same samples.
  eval::SimulationStart carry{0};
  carry.settle_s = 5.0;
  const eval::ValidationResult carried = eval::validateModel(tip, rested, {40}, carry);
  for (int o : {0, 1}) EXPECT_NEAR(by_default.outputs[o].fit_sim, carried.outputs[o].fit_sim, 1e-9) << o;
  // Without the minimum bend the noise is registered as the yaw.
  eval::SimulationStart any_bend;
  any_bend.yaw_registration_min_bend_deg = 0.0;
  const eval::ValidationResult noise_registered = eval::validateModel(tip, rested, {40}, any_bend);
  EXPECT_TRUE(noise_registered.yaw.registered);
  EXPECT_GT(std::abs(noise_registered.yaw.offset / kRadPerDeg - yaw), 10.0);
  // (The tip turned about 40 deg: the simulated steering is off by that on every sample.)
  EXPECT_LT(noise_registered.outputs[1].fit_sim, by_default.outputs[1].fit_sim - 50.0);
  // Started after the rest, the window is on the bent tip: the run's yaw.
  eval::SimulationStart after_rest;
  after_rest.settle_s = 6.0;
  const eval::ValidationResult registered = eval::validateModel(tip, rested, {40}, after_rest);
  EXPECT_TRUE(registered.yaw.registered);
  EXPECT_GT(registered.yaw.bent_share, 0.9);
  EXPECT_NEAR(registered.yaw.offset / kRadPerDeg, yaw, 0.3);
  EXPECT_THROW(eval::validateModel(tip, rested, {40}, eval::SimulationStart{5.0, true, 0.0, -1.0}),
               std::invalid_argument);
}

TEST(Validation, TipFrameSimulationRegistersTheRunsSensorYaw) {
  const DriftRuns runs = yawDriftRuns(0.0);
  const DioPwlObfModel tip = identifyModel({runs.train}, fixedInputSide(OutputFrame::kTipCartesian));
  ASSERT_FALSE(tip.output_level.empty());
  io::Log turned = runs.val;
  const double yaw = 3.0;
  const int steer = turned.columnIndex("steer_deg"), bend = turned.columnIndex("bend_deg");
  turned.data.col(steer).array() += yaw;
  // The registration alone: without the training drift (tiny here, but a turn along the run).
  const eval::SimulationStart none{0}, first{tip.sample_time_s, false}, window{0.5, false};  // 0.5 s: 40 samples
  const eval::ValidationResult base = validateModel(tip, runs.val, {40}, none);
  const eval::ValidationResult carried = validateModel(tip, turned, {40}, none);
  const eval::ValidationResult registered = validateModel(tip, turned, {40}, first);
  const eval::ValidationResult windowed = validateModel(tip, turned, {40}, window);
  const eval::ValidationResult by_default = eval::validateModel(tip, turned, {40});  // 5 s
  // Carried, the 3 deg are a standing error; registered, the fit is the
  // unturned run's (within what the first sample's own error turns).
  EXPECT_LT(carried.outputs[1].fit_sim, base.outputs[1].fit_sim - 5.0);
  EXPECT_NEAR(registered.outputs[1].fit_sim, base.outputs[1].fit_sim, 1.0);
  EXPECT_NEAR(windowed.outputs[1].fit_sim, base.outputs[1].fit_sim, 1.0);
  EXPECT_GT(by_default.outputs[1].fit_sim, carried.outputs[1].fit_sim + 5.0);
  EXPECT_TRUE(std::isnan(by_default.outputs[1].simulated(399)));
  EXPECT_TRUE(std::isfinite(by_default.outputs[1].simulated(400)));
  const Eigen::Index T = turned.samples();
  const Eigen::VectorXd turn = registered.outputs[1].simulated.tail(T - 1) - carried.outputs[1].simulated.tail(T - 1);
  EXPECT_NEAR(turn.mean(), yaw, 0.3);
  EXPECT_LT(turn.maxCoeff() - turn.minCoeff(), 1e-6);  // one rotation for the whole run
  EXPECT_LT(
      (registered.outputs[0].simulated.tail(T - 1) - carried.outputs[0].simulated.tail(T - 1)).cwiseAbs().maxCoeff(),
      1e-9);
  // The k-step predictions turn the model's increments into the sensor's
  // frame too: unturned, bending 40 steps ahead loses the 3 deg as a turn of
  // every increment; registered, both fits are the unturned run's.
  EXPECT_LT(carried.outputs[0].fit_k.at(40), base.outputs[0].fit_k.at(40) - 1.0);
  for (int o : {0, 1}) {
    EXPECT_NEAR(registered.outputs[o].fit_k.at(40), base.outputs[o].fit_k.at(40), 0.05) << o;
    EXPECT_NEAR(windowed.outputs[o].fit_k.at(40), base.outputs[o].fit_k.at(40), 0.05) << o;
    EXPECT_NEAR(by_default.outputs[o].fit_k.at(40), base.outputs[o].fit_k.at(40), 0.1) << o;
  }
  // A window is registered on and not scored.
  EXPECT_TRUE(std::isnan(windowed.outputs[1].simulated(39)));
  EXPECT_TRUE(std::isfinite(windowed.outputs[1].simulated(40)));
  // A tip on the axis at the start has no direction to register: the training yaw stays.
  io::Log on_axis = turned;
  on_axis.data(0, bend) = 0.0;
  const eval::ValidationResult kept = validateModel(tip, on_axis, {40}, first);
  EXPECT_LT((kept.outputs[1].simulated.tail(T - 1) - carried.outputs[1].simulated.tail(T - 1)).cwiseAbs().maxCoeff(),
            1e-9);
  // As logged there is no yaw to tell from the outputs: nothing changes.
  const DioPwlObfModel logged = identifyModel({runs.train}, fixedInputSide(OutputFrame::kAsLogged));
  EXPECT_EQ(eval::validateModel(logged, turned, {40}, first).outputs[1].fit_sim,
            validateModel(logged, turned, {40}, none).outputs[1].fit_sim);
  try {
    eval::validateModel(tip, turned, {40}, eval::SimulationStart{static_cast<double>(T) * tip.sample_time_s});
    ADD_FAILURE() << "accepted a registration window as long as the log";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("yaw registration window"), std::string::npos) << e.what();
  }
  try {  // beyond int64 samples the window was scored as if a few samples long
    eval::validateModel(tip, turned, {40}, eval::SimulationStart{1e18});
    ADD_FAILURE() << "accepted a registration window of 1e18 s";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("(1e+18 s, over 10^15 samples) leaves nothing"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(eval::validateModel(tip, turned, {40}, eval::SimulationStart{-1.0}), std::invalid_argument);
  EXPECT_THROW(eval::validateModel(tip, turned, {40}, eval::SimulationStart{std::nan("")}), std::invalid_argument);
  // So does a simulation without an output level, which starts from the measured sample.
  DioPwlObfModel bare = logged;
  bare.output_level.clear();
  const Eigen::MatrixXd u = turned.columnsOf(bare.inputs), y = turned.columnsOf(bare.outputs);
  const Eigen::MatrixXd dy = eval::modelIncrements(bare, u);
  EXPECT_EQ(eval::simulateModel(bare, u, y, dy, none).size(), 2u);
  EXPECT_THROW(eval::simulateModel(bare, u, y, dy, eval::SimulationStart{-1.0}), std::invalid_argument);
}

// A model fitted with the sensor's yaw drift taken out simulates a new run
// turning at that rate (the default): steering's error no longer grows with
// the run, and the turn is exactly the recorded rate, nothing else.
TEST(Validation, TipFrameSimulationCarriesTheTrainingSensorDrift) {
  const double rate = 0.03;
  const DriftRuns runs = yawDriftRuns(rate), still = yawDriftRuns(0.0);
  const DioPwlObfModel tip = identifyModel({runs.train}, fixedInputSide(OutputFrame::kTipCartesian));
  ASSERT_EQ(tip.training_drift_per_s.size(), 2u);
  ASSERT_NEAR(tip.training_drift_per_s[1], rate, 0.1 * rate);
  const eval::SimulationStart plain{5.0, false};
  EXPECT_EQ(eval::carriedYawRate(tip, eval::SimulationStart{}), tip.training_drift_per_s[1]);
  EXPECT_EQ(eval::carriedYawRate(tip, plain), 0.0);
  EXPECT_EQ(eval::carriedYawRate(tip, eval::SimulationStart{0}), 0.0);  // nothing to anchor the turn on
  const eval::ValidationResult carried = eval::validateModel(tip, runs.val, {40}),
                               left = eval::validateModel(tip, runs.val, {40}, plain);
  // The same model on a run whose sensor does not drift: what steering can reach.
  const eval::ValidationResult reach = validateModel(tip, still.val, {40}, plain);
  EXPECT_GT(carried.outputs[1].fit_sim, left.outputs[1].fit_sim + 5.0);
  EXPECT_NEAR(carried.outputs[1].fit_sim, reach.outputs[1].fit_sim, 2.0);
  const Eigen::Index T = runs.val.samples(), n = T - 400;  // scored after the 5 s registration
  const Eigen::VectorXd turn = carried.outputs[1].simulated.tail(n) - left.outputs[1].simulated.tail(n);
  const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(n, 400, static_cast<double>(T - 1)) * tip.sample_time_s;
  Eigen::MatrixXd A(n, 2);
  A << t, Eigen::VectorXd::Ones(n);
  const Eigen::Vector2d line = A.colPivHouseholderQr().solve(turn);
  EXPECT_NEAR(line(0), tip.training_drift_per_s[1], 1e-9);
  EXPECT_LT((A * line - turn).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((carried.outputs[0].simulated.tail(n) - left.outputs[0].simulated.tail(n)).cwiseAbs().maxCoeff(), 1e-9);
  // Without tracking the k-step predictions turn at the carried drift as
  // well: bending 40 steps ahead reaches what it does on a run whose sensor
  // does not drift, and falls short of it without the drift.
  const eval::SimulationStart untracked{5.0, true, 0.0, 1.0, 0.0}, untracked_plain{5.0, false, 0.0, 1.0, 0.0};
  const double carried_k = eval::validateModel(tip, runs.val, {40}, untracked).outputs[0].fit_k.at(40),
               left_k = eval::validateModel(tip, runs.val, {40}, untracked_plain).outputs[0].fit_k.at(40),
               reach_k = validateModel(tip, still.val, {40}, untracked_plain).outputs[0].fit_k.at(40);
  EXPECT_GT(carried_k, left_k + 0.2);
  EXPECT_NEAR(carried_k, reach_k, 0.05);
  // Tracked (the default), they follow the sensor's yaw whether or not the
  // drift is carried; the simulation is the window's registration either way.
  EXPECT_NEAR(carried.outputs[0].fit_k.at(40), reach.outputs[0].fit_k.at(40), 0.2);
  EXPECT_NEAR(left.outputs[0].fit_k.at(40), reach.outputs[0].fit_k.at(40), 0.2);
  EXPECT_GT(left.outputs[0].fit_k.at(40), left_k + 0.1);
  // As logged a trend has no registration to anchor it: nothing is carried.
  IdentifyOptions o = fixedInputSide(OutputFrame::kAsLogged);
  o.output_drift = OutputDriftChoice::kOn;
  const DioPwlObfModel logged = identifyModel({runs.train}, o);
  ASSERT_FALSE(logged.training_drift_per_s.empty());
  EXPECT_EQ(eval::carriedYawRate(logged, eval::SimulationStart{}), 0.0);
  EXPECT_EQ(eval::validateModel(logged, runs.val, {40}).outputs[1].fit_sim,
            validateModel(logged, runs.val, {40}, plain).outputs[1].fit_sim);
}

// Steering is an angle: a log that writes the same direction a whole turn
// higher from some sample on (a sensor wrapping its angle as the tip passes
// +-180 deg) must leave the simulation's and the k-step predictions' errors
// the same. Each predicted steering angle is written on the branch of the
// measured angle at its sample; a simulation that followed its own previous
// value would stay a turn away from the whole second half, and a k-step
// prediction on the branch of the angle it starts from a turn away from the
// horizon's samples after the wrap.
TEST(Validation, TipFramePredictionsCompareSteeringAsAnAngle) {
  const DriftRuns runs = yawDriftRuns(0.0);
  const DioPwlObfModel tip = identifyModel({runs.train}, fixedInputSide(OutputFrame::kTipCartesian));
  io::Log wrapped = runs.val;
  const Eigen::Index T = wrapped.samples(), half = T / 2;
  const int steer = wrapped.columnIndex("steer_deg");
  wrapped.data.col(steer).tail(T - half).array() += 360.0;
  for (const eval::SimulationStart& start : {eval::SimulationStart{0}, eval::SimulationStart{}}) {
    const eval::ValidationResult base = validateModel(tip, runs.val, {40}, start),
                                 turn = validateModel(tip, wrapped, {40}, start);
    const Eigen::VectorXd shift = turn.outputs[1].simulated - base.outputs[1].simulated;
    const Eigen::Index first = T - base.outputs[1].simulated.array().isFinite().count();
    ASSERT_LT(first, half);
    EXPECT_LT(shift.segment(first, half - first).cwiseAbs().maxCoeff(), 1e-9) << start.yaw_registration_s;
    EXPECT_LT((shift.tail(T - half).array() - 360.0).abs().maxCoeff(), 1e-9) << start.yaw_registration_s;
    // So the simulation's error is the same at every sample (its fit is not:
    // the measured spread grows by the turn).
    const Eigen::VectorXd error_base = (base.outputs[1].measured - base.outputs[1].simulated).tail(T - first),
                          error_turn = (turn.outputs[1].measured - turn.outputs[1].simulated).tail(T - first);
    EXPECT_LT((error_turn - error_base).cwiseAbs().maxCoeff(), 1e-9) << start.yaw_registration_s;
    EXPECT_EQ(turn.outputs[0].fit_sim, base.outputs[0].fit_sim);
    EXPECT_NEAR(turn.outputs[0].fit_k.at(40), base.outputs[0].fit_k.at(40), 1e-9);
    const Eigen::Index k_first = T - base.outputs[1].predicted_k.at(40).array().isFinite().count();
    ASSERT_LT(k_first, half);
    const Eigen::VectorXd k_base = (base.outputs[1].measured - base.outputs[1].predicted_k.at(40)).tail(T - k_first),
                          k_turn = (turn.outputs[1].measured - turn.outputs[1].predicted_k.at(40)).tail(T - k_first);
    EXPECT_LT((k_turn - k_base).cwiseAbs().maxCoeff(), 1e-9) << start.yaw_registration_s;
    EXPECT_NEAR(turn.outputs[1].rms_k.at(40), base.outputs[1].rms_k.at(40), 1e-9) << start.yaw_registration_s;
  }
}

// Validation counts the samples beyond the grid's outer nodes per input,
// not only those beyond the training range: a run recorded from rest spans
// 0 while its grid starts higher.
TEST(Validation, ReportsSamplesBeyondTheGridPerInput) {
  DioPwlObfModel m;
  m.inputs = {"p_1", "p_2"};
  m.input_ranges = {{0.0, 0.4}, {0.0, 0.4}};
  m.partition = PwlPartition::interpolated({0}, {{0.2, 0.3, 0.4}});
  Eigen::MatrixXd u(10, 2);
  u.col(0) << 0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45;
  u.col(1).setConstant(0.1);
  const eval::InputsOutsideTraining c = eval::inputsOutsideTraining(m, u);
  EXPECT_DOUBLE_EQ(c.each[0], 0.1);  // 0.45 alone is beyond the range
  ASSERT_TRUE(c.on_grid[0]);
  EXPECT_FALSE(c.on_grid[1]);
  EXPECT_DOUBLE_EQ(c.below_grid[0], 0.4);
  EXPECT_DOUBLE_EQ(c.above_grid[0], 0.1);
  EXPECT_DOUBLE_EQ(c.any_beyond_grid, 0.5);
  const std::vector<std::string> w = eval::inputCoverageWarnings(m, c);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("p_1 is below the training grid's lowest node 0.2 on 40.0%"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("above its highest node 0.4 on 10.0%"), std::string::npos) << w[0];
  // A switched partition has no nodes: only the range is reported.
  m.partition = PwlPartition({0}, {{0.25, 0.35}});
  const eval::InputsOutsideTraining s = eval::inputsOutsideTraining(m, u);
  EXPECT_FALSE(s.on_grid[0]);
  EXPECT_DOUBLE_EQ(s.any_beyond_grid, 0.0);
  EXPECT_NE(inputCoverageWarnings(m, s).at(0).find("outside its training range [0, 0.4] on 10.0%"), std::string::npos);
}

// A simulation that leaves the measured range by more than half its width is
// named with how far and when; one that follows the run, error and all, is not.
TEST(Validation, NamesASimulationThatLeavesTheMeasuredRange) {
  const Eigen::Index n = 200;
  eval::ValidationResult v;
  v.time = Eigen::VectorXd::LinSpaced(n, 0.0, 0.0125 * static_cast<double>(n - 1));
  v.scored_from = 10;
  eval::OutputValidation follows, departs;
  follows.name = "steering";
  departs.name = "bending";
  follows.measured = (v.time.array() * 2.0).sin().matrix() * 10.0;  // spans [-10, 10]
  follows.simulated = follows.measured.array() * 1.4;               // 4 beyond: 20% of the width
  departs.measured = follows.measured;
  departs.simulated = follows.measured;
  // From t = 1.25 s on it runs away: 11 beyond the range's top at sample 110 (0.55 of 20).
  for (Eigen::Index k = 100; k < n; ++k) departs.simulated(k) = 10.0 + static_cast<double>(k - 99) * 1.0;
  v.outputs = {follows, departs};
  const std::vector<eval::SimulationDeparture> d = eval::simulationDepartures(v);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].output, "bending");
  EXPECT_NEAR(d[0].measured_low, follows.measured.segment(10, n - 10).minCoeff(), 1e-12);
  EXPECT_NEAR(d[0].farthest, 110.0 - d[0].measured_high, 1e-9);
  EXPECT_NEAR(d[0].share, d[0].farthest / (d[0].measured_high - d[0].measured_low), 1e-12);
  // First beyond half the width: the first sample more than ~10 above the top.
  const double half = 0.5 * (d[0].measured_high - d[0].measured_low);
  Eigen::Index first = 100;
  while (departs.simulated(first) - d[0].measured_high <= half) ++first;
  EXPECT_DOUBLE_EQ(d[0].first_time_s, v.time(first));
  const std::vector<std::string> w = eval::simulationWarnings(d);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("the free simulation of bending leaves the measured range"), std::string::npos) << w[0];
  // A tighter tolerance names the 20% overshoot too; a departure before the
  // scored samples is not counted.
  EXPECT_EQ(simulationDepartures(v, 0.1).size(), 2u);
  v.outputs[1].simulated.head(10).setConstant(1e6);
  EXPECT_EQ(simulationDepartures(v).size(), 1u);
  v.outputs[1].simulated.segment(100, 100) = v.outputs[1].measured.segment(100, 100);
  EXPECT_TRUE(simulationDepartures(v).empty());
  expectThrowContaining([&] { simulationDepartures(v, 0.0); }, "tolerance");
  expectThrowContaining([&] { simulationDepartures(v, std::nan("")); }, "tolerance");
}

// Why a k-step fit can fall below the simulation's: restarted from the
// measured output, its error is e(t) - e(t-h) of the simulation's error e.
// An error that persists cancels; one that changes within the horizon counts
// twice. The k-step error is the smaller exactly when simulationErrorKept > 1/2.
TEST(Validation, TheSimulationErrorKeptSaysWhenAKStepPredictionLosesToTheSimulation) {
  const Eigen::Index T = 4000;
  const int h = 80;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  const Eigen::VectorXd truth = Eigen::VectorXd::LinSpaced(T, 0.0, 60.0).array().sin() * 10.0;
  for (const double slow_share : {0.1, 0.5, 0.9}) {
    // The model's error: a slow wander (persists over h) and a fast part (does not), in that proportion.
    Eigen::VectorXd e(T);
    double wander = 0.0;
    for (Eigen::Index t = 0; t < T; ++t) {
      wander = 0.999 * wander + 0.045 * noise(rng);
      e(t) = slow_share * wander + (1.0 - slow_share) * 0.5 * noise(rng);
    }
    const Eigen::VectorXd y = truth + e;
    Eigen::VectorXd dyhat = Eigen::VectorXd::Zero(T);  // the model's increments: the truth's
    dyhat.tail(T - 1) = truth.tail(T - 1) - truth.head(T - 1);
    const eval::AlignedPrediction k = eval::kStepAhead(y, dyhat, h), sim = eval::simulate(y, dyhat);
    const Eigen::VectorXd k_full = eval::placedOver(k, T), sim_full = eval::placedOver(sim, T);
    const Eigen::Index from = h + 1;
    const double kept = eval::simulationErrorKept(y, sim_full, from, h);
    const double sse_k = (y - k_full).tail(T - from).squaredNorm(),
                 sse_sim = (y - sim_full).tail(T - from).squaredNorm();
    EXPECT_EQ(sse_k<sse_sim, kept> 0.5) << "slow share " << slow_share << ": kept " << kept;
    // Exactly: sse_k - sse_sim = (1 - 2 kept) * sum e(t-h)^2.
    const Eigen::VectorXd es = y - sim_full;
    EXPECT_NEAR(sse_k - sse_sim, (1.0 - 2.0 * kept) * es.segment(from - h, T - from).squaredNorm(), 1e-9 * sse_sim);
    if (slow_share == 0.1) {
      EXPECT_LT(kept, 0.5) << "a fast error: the k-step prediction loses";
    }
    if (slow_share == 0.9) {
      EXPECT_GT(kept, 0.5) << "a slow error: the k-step prediction wins";
    }
  }
  EXPECT_TRUE(std::isnan(eval::simulationErrorKept(truth, truth, 0, h))) << "no error: nothing to keep";
}

// A log that does not start at rest: the simulation starts settled at its
// first inputs, so the actuator's motion at the log's start is an error the
// model did not make. It is named, with the settling time that leaves it out
// of the scores; a log recorded from rest, noise and all, is not named.
TEST(Validation, NamesALogThatDoesNotStartAtRestAndSettlesIt) {
  hand_built::Spec spec;  // an input-side model with an output level: the simulation from the inputs alone
  spec.poles = {{0.995, 0.0}, {0.98, 0.0}};  // a 2.5 s mode
  spec.side = ScheduleSide::kInput;
  spec.grid = hand_built::Grid::kLevels;
  spec.levels = {{0.0, 0.6}};
  DioPwlObfModel m = hand_built::build(spec);
  m.output_level = {1.0};
  const Eigen::Index T = 8000, hold = 400;  // 100 s at 80 Hz, a level every 5 s
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> level(0.0, 0.6);
  std::normal_distribution<double> noise(0.0, 0.002);
  Eigen::MatrixXd u(T, 1);
  for (Eigen::Index k = 0; k < T; k += hold) u.col(0).segment(k, hold).setConstant(k == 0 ? 0.0 : level(rng));
  u.col(0).segment(hold, hold).setConstant(0.6);  // a full step at 5 s
  const Eigen::VectorXd truth = eval::modelTip(m, u, eval::modelIncrements(m, u)).col(0);
  io::Log from_rest;
  from_rest.source = "from_rest.csv";
  from_rest.columns = {"time_s", "u1", "y1"};
  from_rest.data.resize(T, 3);
  for (Eigen::Index k = 0; k < T; ++k)
    from_rest.data.row(k) << static_cast<double>(k) * m.sample_time_s, u(k, 0), truth(k) + noise(rng);
  const eval::ValidationResult rest = eval::validateModel(m, from_rest, {40});
  EXPECT_TRUE(rest.unsettled_starts.empty());
  EXPECT_GT(rest.outputs[0].fit_sim, 95.0);
  // The same run logged from 0.1 s after the step on: the mode still moves.
  io::Log moving = from_rest;
  moving.source = "moving.csv";
  moving.data = from_rest.data.bottomRows(T - hold - 8);
  const eval::ValidationResult v = eval::validateModel(m, moving, {40});
  ASSERT_EQ(v.unsettled_starts.size(), 1u);
  const eval::UnsettledStart& t = v.unsettled_starts[0];
  EXPECT_EQ(t.output, "y1");
  EXPECT_EQ(t.later_s, 5.0);
  EXPECT_DOUBLE_EQ(t.rms_error, v.outputs[0].rms_sim);
  EXPECT_LT(t.rms_later, 0.8 * t.rms_error);
  const std::vector<std::string> w = eval::unsettledStartWarnings(v.unsettled_starts);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("may not start at rest"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("--settle 5 "), std::string::npos) << w[0];
  EXPECT_EQ(t.straight_share, 0.0);  // not a tip-frame model
  // Settled for 15 s (three of the mode's time constants past the 5 s):
  // scored from there on, nothing named, the fits up.
  eval::SimulationStart settled;
  settled.settle_s = 15.0;
  const eval::ValidationResult s = eval::validateModel(m, moving, {40}, settled);
  EXPECT_EQ(s.scored_from, 1200);
  EXPECT_TRUE(s.unsettled_starts.empty());
  EXPECT_GT(s.outputs[0].fit_sim, v.outputs[0].fit_sim + 5.0);
  EXPECT_GT(s.outputs[0].fit_sim, 95.0);
  EXPECT_GT(s.outputs[0].fit_k.at(40), v.outputs[0].fit_k.at(40));
  for (const double bad : {-1.0, std::nan(""), 1e6, 1e18}) {  // 1e18 s overflowed to bad_alloc
    settled.settle_s = bad;
    expectThrowContaining([&] { eval::validateModel(m, moving, {40}, settled); }, "settling time");
  }
  settled.settle_s = 1e18;
  expectThrowContaining([&] { eval::validateModel(m, moving, {40}, settled); }, "is over 10^15 samples of the log's");
}

// A model without an output level simulates from the measured sample it
// starts at: an unsettled start leaves it a lasting offset, and the settling
// time restarts it from the measured sample at its end.
TEST(Validation, SettlingRestartsASimulationFromTheMeasuredSample) {
  DioPwlObfModel m = knownModel();
  const Eigen::Index T = 4000;
  Eigen::MatrixXd u(T, 1);
  for (Eigen::Index k = 0; k < T; ++k) u(k, 0) = (k / 200) % 2 == 0 ? 0.2 : 0.8;
  const Eigen::VectorXd dy = eval::modelIncrements(m, u).col(0);
  io::Log log;
  log.source = "moving.csv";
  log.columns = {"time_s", "u", "y"};
  log.data.resize(T, 3);
  double y = 0.0;
  for (Eigen::Index k = 0; k < T; ++k) {
    y += k > 0 ? dy(k) : 0.0;
    log.data.row(k) << static_cast<double>(k) * m.sample_time_s, u(k, 0), y;
  }
  log.data = log.data.bottomRows(T - 202).eval();  // 2 samples after a step: the filters still move
  const eval::ValidationResult v = eval::validateModel(m, log, {1});
  EXPECT_LT(v.outputs[0].fit_sim, 90.0) << "the unsettled start's offset";
  ASSERT_EQ(v.unsettled_starts.size(), 1u) << "named: started later, the offset is gone";
  EXPECT_LT(v.unsettled_starts[0].rms_later, 1e-6);
  eval::SimulationStart settled;
  settled.settle_s = 2.0;  // 160 samples: the 0.9 and 0.7 modes gone to 1e-7
  const eval::ValidationResult s = eval::validateModel(m, log, {1}, settled);
  EXPECT_EQ(s.scored_from, 161) << "the first simulated sample after the one it restarts from";
  EXPECT_GT(s.outputs[0].fit_sim, 99.99);
  const Eigen::VectorXd cut_dy = eval::modelIncrements(m, log.columnsOf({"u"})).col(0);
  EXPECT_NEAR(s.outputs[0].simulated(161), log.data(160, 2) + cut_dy(161), 1e-12)
      << "restarted from the measured sample at 2 s";
}
