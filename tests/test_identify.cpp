// Identification end to end: the pipeline and its structure search on simulated runs.
#include "plsa/identify/baselines.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;
using namespace plsa::test_fixtures;
using C = std::complex<double>;

// The paper's protocol on the simulated actuator with its effects switched off:
// what remains (pneumatics, nonlinear elongation, kinematics, noise) must be
// predicted well. Floors sit well under the measured values (docs/identification.md).
TEST(Pipeline, SimulatedActuatorWithoutEffects) {
  sim::SimConfig c;
  for (const auto& e : sim::effectNames()) c.setEffectEnabled(e, false);
  sim::ExperimentOptions eo;
  eo.seed = 2;
  sim::Actuator a(c, 1), b(c, 2);
  const io::Log train = sim::runExperiment(a, sim::gridExperiment(eo));
  const io::Log val = sim::runExperiment(b, sim::joystickExperiment(eo));
  IdentifyReport rep;
  const IdentifyOptions defaults;
  const DioPwlObfModel m = identifyModel({train}, defaults, &rep);
  EXPECT_EQ(rep.coefficients.regions_fitted, 16);
  EXPECT_FALSE(rep.used_windows);
  for (const auto& pp : rep.pairs)
    for (const auto& p : pp.chosen.centres) {
      EXPECT_GT(p.real(), 0.7);
      EXPECT_LT(std::abs(p), 1.0);
    }
  const eval::ValidationResult v = eval::validateModel(m, val, {40, 80});
  for (const auto& o : v.outputs) {
    EXPECT_GT(o.fit_k.at(40), 93.0) << o.name;
    EXPECT_GT(o.fit_k.at(80), 90.0) << o.name;
  }
  // A bad cross-validation layout or chunk is named, not guessed around.
  IdentifyOptions bad;
  bad.cv_layout = static_cast<CvLayout>(7);  // a cast from an integer
  expectThrowContaining([&] { identifyModel({train}, bad); },
                        "cross-validation layout 7 is none of interleaved or contiguous");
  expectThrowContaining([&] { parseOption<CvLayout>("random"); },
                        "cross-validation layout 'random': expected interleaved or contiguous");
  EXPECT_EQ(parseOption<SchedulingChoice>("input"), SchedulingChoice::kInputSide);
  EXPECT_STREQ(optionName(PoleMethod::kFuzzyCMeans), "fcm");
  bad.cv_layout = CvLayout::kInterleaved;
  bad.cv_chunk_s = 0.0;
  expectThrowContaining([&] { identifyModel({train}, bad); }, "chunks must last");
}

// Stage 5 on a long log runs for minutes between its summary lines; with an
// interval of 0 every held-out score prints where its stage is, so each
// stage's count must run 1..N with N the candidates it tries.
TEST(Pipeline, ProgressCountsEveryHeldOutScoreOfEachStage) {
  sim::SimConfig c;
  for (const auto& e : sim::effectNames()) c.setEffectEnabled(e, false);
  sim::ExperimentOptions eo;
  eo.seed = 3;
  sim::Actuator a(c, 1);
  const io::Log train = sim::runExperiment(a, sim::gridExperiment(eo));
  IdentifyOptions o;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{0.0}, {0.1}};  // no growing set: the threshold stage tries the chosen set only
  o.play_coupling_candidates = {0.3};
  o.schedule_lag_candidates = {0.2};
  o.play_threshold_candidates = {0.2};
  o.slow_pole_candidates = {0.0, 5.0};        // 0 is "none", scored once
  o.output_drift = OutputDriftChoice::kAuto;  // scored twice
  o.progress_interval_s = 0.0;
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({train}, o, &rep);
  std::vector<std::string> ticks;
  for (const std::string& l : rep.lines)
    if (l.rfind("[5/5] scoring ", 0) == 0) ticks.push_back(l.substr(14, l.find(" held-out") - 14));
  // The default bank of plays uncoupled and, when the coupling stage kept
  // one, with it; the chosen set's held-out terms are kept from its stage.
  const std::size_t banks = rep.play_bank_scores.size();
  ASSERT_EQ(banks, m.shaping.coupling > 0 ? 2u : 1u);
  const std::string bank_total = " of " + std::to_string(banks);
  std::vector<std::string> expected{"pole methods: 1 of 4",  // two each: 40 steps ahead, simulated
                                    "pole methods: 2 of 4",
                                    "pole methods: 3 of 4",
                                    "pole methods: 4 of 4",
                                    "play channels and scheduling: 1 of 2",
                                    "play channels and scheduling: 2 of 2",
                                    "coupled play channels: 1 of 2",
                                    "coupled play channels: 2 of 2",
                                    "banks of plays: 1" + bank_total,
                                    "scheduling lags: 1 of 1",
                                    "play thresholds: 1 of 1",
                                    "sensor drift: 1 of 2",
                                    "sensor drift: 2 of 2",
                                    "slow poles: 1 of 2",
                                    "slow poles: 2 of 2"};
  // With the drift left in, the slow poles' "none" is the drift stage's
  // score as logged (the same model), not scored again.
  if (!rep.drift_taken_out) {
    expected.resize(expected.size() - 2);
    expected.push_back("slow poles: 1 of 1");
    ASSERT_FALSE(rep.slow_pole_scores.empty());
    EXPECT_EQ(rep.slow_pole_scores.front().second, rep.drift_scores.first);
  }
  if (banks == 2)
    expected.insert(std::find(expected.begin(), expected.end(), "scheduling lags: 1 of 1"), "banks of plays: 2 of 2");
  EXPECT_EQ(ticks, expected);
  // An interval longer than the run prints none.
  o.progress_interval_s = 1e6;
  IdentifyReport quiet;
  identifyModel({train}, o, &quiet);
  for (const std::string& l : quiet.lines) EXPECT_EQ(l.rfind("[5/5] scoring ", 0), std::string::npos) << l;
  o.progress_interval_s = -1.0;
  expectThrowContaining([&] { identifyModel({train}, o); }, "progress interval");
  o.progress_interval_s = std::nan("");
  expectThrowContaining([&] { identifyModel({train}, o); }, "progress interval");
}

// Noise-free first-order data: every schedule lag scores the same to rounding
// (100.00), and such a tie keeps the shortest (none), whatever order the lags
// are listed in (it kept 0.8 s, the last, on a probe's log).
TEST(Pipeline, ScheduleLagsThatTieKeepNone) {
  io::Log log;
  log.source = "first_order.csv";
  log.columns = {"time_s", "u_1", "y_1"};
  log.data.setZero(3000, 3);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> level(0.0, 0.4), hold(2.0, 5.0);
  double u = 0.0, y = 0.0, next_step = 1.0;
  for (Eigen::Index k = 0; k < log.data.rows(); ++k) {
    const double t = 0.1 * static_cast<double>(k);
    if (t >= next_step) {
      u = level(rng);
      next_step = t + hold(rng);
    }
    log.data.row(k) << t, u, y;
    y = 0.8172 * y + 0.1828 * u;
  }
  IdentifyOptions o;
  o.inputs = {"u_1"};
  o.outputs = {"y_1"};
  o.schedule_lag_candidates = {0.8, 0.1, 0.4};
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({log}, o, &rep);
  EXPECT_EQ(m.schedule_lag_s, 0.0);
  ASSERT_EQ(rep.schedule_lag_scores.size(), 4u);
  for (std::size_t i = 1; i < rep.schedule_lag_scores.size(); ++i) {
    EXPECT_GT(rep.schedule_lag_scores[i].first, rep.schedule_lag_scores[i - 1].first) << "tried shortest first";
    EXPECT_NEAR(rep.schedule_lag_scores[i].second, rep.schedule_lag_scores[0].second, 0.01) << "a tie";
  }
}

// All effects on, the paper's protocol as `plsa demo` runs it (seed 1). The
// level-growing, coupled play band and the rising start must hold their
// gain over the paper's configuration (measured 93.8/94.3 at 40 steps and
// 90.5/91.1 at 80 against 75.9/82.3 and 58.6/69.0; docs/identification.md
// gives the simulation cells of seeds 1 to 8).
// With every effect off the simulator's nonlinearity is its kinematics, which
// act on the bending state, after the dynamics: scheduled on the raw inputs,
// the coefficients run ahead of that state while the inputs move, and the
// integrated increments drift. A lag about as slow as the bending mode keeps
// them with it (docs/identification.md).
TEST(Pipeline, ScheduleLagStopsTheSimulationDriftOfAStateSideNonlinearity) {
  sim::SimConfig clean;
  for (const std::string& e : sim::effectNames()) clean.setEffectEnabled(e, false);
  sim::ExperimentOptions eo;
  sim::Actuator a(clean, 1), b(clean, 102);
  const io::Log train = sim::runExperiment(a, sim::gridExperiment(eo));
  // Joystick paths 101 to 103 measured: raw 24-82% (bending) and 57-74%
  // (steering) in simulation, lagged 91-94% and 95-96%. The default path
  // happens not to drift on steering (98% raw, 95% lagged).
  eo.seed = 102;
  const io::Log val = sim::runExperiment(b, sim::joystickExperiment(eo));
  IdentifyOptions o;
  o.scheduling = SchedulingChoice::kInterpolated;
  o.play_candidates = {{0.0}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  const DioPwlObfModel raw = identifyModel({train}, o);
  EXPECT_EQ(raw.schedule_lag_s, 0.0);
  o.schedule_lag_candidates = {0.4};
  IdentifyReport rep;
  const DioPwlObfModel lagged = identifyModel({train}, o, &rep);
  EXPECT_EQ(lagged.schedule_lag_s, 0.4) << "cross-validation should keep the lag";
  ASSERT_EQ(rep.schedule_lag_scores.size(), 2u);
  EXPECT_GT(rep.schedule_lag_scores[1].second, rep.schedule_lag_scores[0].second);
  const eval::ValidationResult v = eval::validateModel(lagged, val, {40});
  const eval::ValidationResult w = eval::validateModel(raw, val, {40});
  for (std::size_t i = 0; i < v.outputs.size(); ++i) {
    EXPECT_GT(v.outputs[i].fit_sim, 88.0) << v.outputs[i].name;
    EXPECT_GT(v.outputs[i].fit_sim, w.outputs[i].fit_sim + 10.0) << v.outputs[i].name;
    EXPECT_GE(v.outputs[i].fit_k.at(40), w.outputs[i].fit_k.at(40) - 0.5) << v.outputs[i].name;
  }
}

// Input side, the increments are exact differences of one static map
// followed by stable filters: an input path that wanders and comes back
// returns the simulated output to where it started, whatever the
// coefficients. Output side (the paper's structure) it does not.
TEST(Pipeline, InputSideSchedulingReturnsTheOutputWhenTheInputsReturn) {
  sim::SimConfig clean;
  for (const std::string& e : sim::effectNames()) clean.setEffectEnabled(e, false);
  sim::ExperimentOptions eo;
  eo.hold_s = 2.0;
  sim::Actuator a(clean, 1);
  const io::Log train = sim::runExperiment(a, sim::gridExperiment(eo));
  IdentifyOptions o;
  o.output_frame = OutputFrame::kAsLogged;  // the levels below are compared in the logged angles
  o.play_candidates = {{0.0}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  o.slow_pole_candidates = {};  // a slow pole's decay would outlast the hold below
  o.scheduling = SchedulingChoice::kInputSide;
  const DioPwlObfModel input_side = identifyModel({train}, o);
  ASSERT_EQ(input_side.schedule_side, ScheduleSide::kInput);
  o.scheduling = SchedulingChoice::kInterpolated;
  const DioPwlObfModel output_side = identifyModel({train}, o);
  ASSERT_EQ(output_side.schedule_side, ScheduleSide::kOutput);
  // 30 s of random wandering over the grid, back to the start, then 30 s held.
  std::mt19937 rng(7);
  std::normal_distribution<double> step(0.0, 0.004);
  const int wander = 2400, hold = 2400;
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(wander + hold, 3);
  u.row(0) << 0.25, 0.3, 0.0;
  for (int k = 1; k < wander; ++k)
    for (int j = 0; j < 2; ++j) u(k, j) = std::clamp(u(k - 1, j) + step(rng), 0.2, 0.35);
  for (int k = wander; k < wander + hold; ++k) u.row(k) = u.row(0);
  const Eigen::MatrixXd di = eval::modelIncrements(input_side, u), dout = eval::modelIncrements(output_side, u);
  for (int out = 0; out < 2; ++out) {
    const double travel = di.col(out).cwiseAbs().sum();
    EXPECT_GT(travel, 5.0) << "the output should move along the way";
    EXPECT_LT(std::abs(di.col(out).sum()), 1e-9 * travel) << input_side.outputs[static_cast<std::size_t>(out)];
    EXPECT_GT(std::abs(dout.col(out).sum()), 1e-3 * travel) << "output side should not close the loop here";
  }
  // The model file keeps the side.
  EXPECT_EQ(modelFromJson(modelToJson(input_side)).schedule_side, ScheduleSide::kInput);

  // Its level is a function of the inputs: increments of modelLevels are the
  // model's increments, and level plus output_level is the settled output.
  ASSERT_EQ(input_side.output_level.size(), 2u);
  EXPECT_TRUE(output_side.output_level.empty());
  const Eigen::MatrixXd level = eval::modelLevels(input_side, u);
  EXPECT_LT(((level.bottomRows(u.rows() - 1) - level.topRows(u.rows() - 1)) - di.bottomRows(u.rows() - 1))
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  // The settled start depends on the first sample alone: the same as from the whole record's regressors.
  const eval::ModelRegressors whole = eval::modelRegressors(input_side, u);
  for (int out = 0; out < 2; ++out)
    EXPECT_NEAR(level(0, out), whole.level0[static_cast<std::size_t>(out)].dot(input_side.stackedCoefficients(out)),
                1e-9);
  sim::Actuator held(clean, 3);
  sim::ActuatorSample settled;
  for (int k = 0; k < 800; ++k) settled = held.step({u(0, 0), u(0, 1), u(0, 2)});
  const double truth[2] = {settled.bend_deg, settled.steer_deg};
  for (int out = 0; out < 2; ++out)  // 0.07 and 0.06 degrees apart when written
    EXPECT_NEAR(input_side.output_level[static_cast<std::size_t>(out)] + level(u.rows() - 1, out), truth[out], 0.3);
  EXPECT_EQ(modelFromJson(modelToJson(input_side)).output_level, input_side.output_level);
}

// A tip's angles logged in radians under names that give no unit (theta and
// phi, as constant-curvature papers write them) are read as radians: the
// model is the degrees' model in radians (the same structure and drift, the
// same fits held out). Taken for degrees, as they were before the unit was
// read, the steering's simulation fit fell from 95 to 86 on a joystick run
// of the independent actuator.
TEST(Pipeline, TipAnglesInRadiansIdentifyAsInDegrees) {
  const double rate = 0.03;
  const DriftRuns runs = yawDriftRuns(rate);
  auto inRadians = [](io::Log log) {
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"bend_deg", "theta"}, {"steer_deg", "phi"}}) {
      const int c = log.columnIndex(from);
      log.columns[static_cast<std::size_t>(c)] = to;
      log.data.col(c) *= kRadPerDeg;
    }
    return log;
  };
  IdentifyOptions o = fixedInputSide(OutputFrame::kTipCartesian);
  o.output_frame.reset();  // chosen from the names and the data
  IdentifyReport rep_deg, rep_rad;
  const DioPwlObfModel deg = identifyModel({runs.train}, o, &rep_deg);
  o.outputs = {"theta", "phi"};
  const DioPwlObfModel rad = identifyModel({inRadians(runs.train)}, o, &rep_rad);
  EXPECT_EQ(rep_deg.output_frame.angle_unit, "deg");
  ASSERT_EQ(rep_rad.output_frame.frame, OutputFrame::kTipCartesian);
  EXPECT_EQ(rep_rad.output_frame.angle_unit, "rad");
  EXPECT_EQ(deg.output_unit, "deg");
  EXPECT_EQ(rad.output_unit, "rad");
  EXPECT_EQ(modelFromJson(modelToJson(rad)).output_unit, "rad");
  EXPECT_EQ(rad.partition.regionCount(), deg.partition.regionCount());
  EXPECT_EQ(rep_rad.drift_taken_out, rep_deg.drift_taken_out);
  ASSERT_TRUE(rep_rad.drift_taken_out) << "the drift stage did not run in either unit";
  EXPECT_NEAR(rad.training_drift_per_s[1], deg.training_drift_per_s[1] * kRadPerDeg, 1e-3 * rate * kRadPerDeg);
  const eval::ValidationResult vd = eval::validateModel(deg, runs.val, {40}),
                               vr = eval::validateModel(rad, inRadians(runs.val), {40});
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(vr.outputs[i].fit_k.at(40), vd.outputs[i].fit_k.at(40), 1e-3) << vd.outputs[i].name;
    EXPECT_NEAR(vr.outputs[i].fit_sim, vd.outputs[i].fit_sim, 1e-3) << vd.outputs[i].name;
  }
  // The option overrides the data; a unit that is neither is refused by name.
  o.angle_unit = "deg";
  IdentifyReport rep_as_deg;
  EXPECT_EQ(identifyModel({inRadians(runs.train)}, o, &rep_as_deg).output_unit, "deg");
  EXPECT_EQ(rep_as_deg.output_frame.angle_unit_reason, "as given");
  o.angle_unit = "grad";
  expectThrowContaining([&] { identifyModel({runs.train}, o); }, "deg or rad");
}

// A staircase logged without its commands: the measured pressures are the
// only references, and their noise cuts them at nearly every sample. Their
// plateaus give the steps and the grid the commands give, and so the same
// model, within a tenth of a point held out (0.002-0.02 when written). As logged they gave no
// step: on the independent actuator's nominal case the steering's
// simulation fit was 77.5 where the commands give 95.2.
TEST(Pipeline, StaircaseWithoutCommandsStepsOnThePressuresPlateaus) {
  const DriftRuns runs = yawDriftRuns(0.0);
  // A pressure sensor three times as noisy as the simulator's, as the
  // independent actuator's: as logged, no pressure holds within the 5 mbar
  // step for 1 s.
  io::Log noisy = runs.train;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.003);
  for (const std::string& p : io::standard_columns::pressures()) {
    const int c = noisy.columnIndex(p);
    for (Eigen::Index k = 0; k < noisy.samples(); ++k) noisy.data(k, c) += noise(rng);
  }
  io::Log pressures_only = noisy;
  std::vector<Eigen::Index> keep;
  std::vector<std::string> names;
  for (std::size_t c = 0; c < noisy.columns.size(); ++c)
    if (noisy.columns[c].rfind("cmd_", 0) != 0) {
      keep.push_back(static_cast<Eigen::Index>(c));
      names.push_back(noisy.columns[c]);
    }
  ASSERT_LT(names.size(), noisy.columns.size()) << "the run logs no commands to drop";
  pressures_only.data = Eigen::MatrixXd(noisy.data(Eigen::all, keep));
  pressures_only.columns = names;
  const IdentifyOptions o = fixedInputSide(OutputFrame::kTipCartesian);
  IdentifyReport with, without;
  const DioPwlObfModel commanded = identifyModel({noisy}, o, &with);
  const DioPwlObfModel plateaus = identifyModel({pressures_only}, o, &without);
  EXPECT_FALSE(with.references_from_plateaus);
  EXPECT_TRUE(without.references_from_plateaus);
  EXPECT_EQ(without.segments, with.segments);
  ASSERT_EQ(plateaus.partition.regionCount(), commanded.partition.regionCount());
  for (std::size_t j = 0; j < commanded.partition.breakpoints().size(); ++j)
    for (std::size_t b = 0; b < commanded.partition.breakpoints()[j].size(); ++b)
      EXPECT_NEAR(plateaus.partition.breakpoints()[j][b], commanded.partition.breakpoints()[j][b], 0.002);
  const eval::ValidationResult vc = eval::validateModel(commanded, runs.val, {40}),
                               vp = eval::validateModel(plateaus, runs.val, {40});
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(vp.outputs[i].fit_k.at(40), vc.outputs[i].fit_k.at(40), 0.1) << vc.outputs[i].name;
    EXPECT_NEAR(vp.outputs[i].fit_sim, vc.outputs[i].fit_sim, 0.1) << vc.outputs[i].name;
  }
  const auto line = std::find_if(without.lines.begin(), without.lines.end(), [](const std::string& l) {
    return l.find("[2/5] step references:") != std::string::npos;
  });
  ASSERT_NE(line, without.lines.end());
  EXPECT_NE(line->find(std::to_string(without.segments) + " step segments"), std::string::npos) << *line;
}

// A yaw drift turns the tip frame: with tip_cartesian the stage reads one
// yaw rate; as logged (forced "on"), the steering angle's own trend. Both
// must find the simulator's rate; in the tip frame it must be kept and lift
// the simulation. With no drift the estimate must be near zero and the drift
// left in.
TEST(Pipeline, SensorYawDriftIsFoundInEitherFrameAndTakenOut) {
  const double rate = 0.03;
  const DriftRuns runs = yawDriftRuns(rate);
  for (OutputFrame frame : {OutputFrame::kTipCartesian, OutputFrame::kAsLogged}) {
    const bool tip = frame == OutputFrame::kTipCartesian;
    IdentifyOptions o = fixedInputSide(frame);
    o.output_drift = tip ? OutputDriftChoice::kAuto : OutputDriftChoice::kOn;
    IdentifyReport rep;
    const DioPwlObfModel taken = identifyModel({runs.train}, o, &rep);
    ASSERT_EQ(rep.output_drift.rate.size(), 2u);
    EXPECT_NEAR(rep.output_drift.rate[1], rate, 0.1 * rate) << toString(frame);  // 0.02997 and 0.03025 when written
    EXPECT_NEAR(rep.output_drift.rate[0], 0.0, 0.1 * rate) << toString(frame);   // a yaw leaves the bend alone
    EXPECT_TRUE(rep.drift_taken_out) << toString(frame);
    EXPECT_EQ(taken.training_drift_per_s, rep.output_drift.rate) << toString(frame);  // recorded in the model
    if (!tip) continue;  // as logged the trend barely moves an angle model's fit (83.02 -> 83.04 held out)
    EXPECT_GT(rep.drift_scores.second, rep.drift_scores.first);
    // Taken out by the one-standard-error rule: the paired gain is the
    // difference of the two scores and exceeds its error.
    EXPECT_NEAR(rep.drift_gain.first, rep.drift_scores.second - rep.drift_scores.first, 1e-9);
    EXPECT_GT(rep.drift_gain.first, rep.drift_gain.second);
    // The progress line gives the gain, its error and each output's.
    const auto line = std::find_if(rep.lines.begin(), rep.lines.end(), [](const std::string& l) {
      return l.find("[5/5] sensor drift over") != std::string::npos;
    });
    ASSERT_NE(line, rep.lines.end());
    const std::string scores = line->substr(std::min(line->size(), line->find(" (held-out")));
    EXPECT_NE(scores.find(": gains "), std::string::npos) << *line;
    EXPECT_NE(scores.find(" +- "), std::string::npos) << *line;
    for (const std::string& out : o.outputs) EXPECT_NE(scores.find(out + " "), std::string::npos) << *line;
    o.output_drift = OutputDriftChoice::kOff;
    IdentifyReport rep_off;
    const DioPwlObfModel left = identifyModel({runs.train}, o, &rep_off);
    EXPECT_TRUE(rep_off.output_drift.rate.empty());
    EXPECT_FALSE(rep_off.drift_taken_out);
    EXPECT_TRUE(left.training_drift_per_s.empty());
    // Simulated carrying the training run's yaw, so that steering shows what
    // the drift did to the model's level.
    const eval::SimulationStart carry{0};
    const eval::ValidationResult v = validateModel(taken, runs.val, {40}, carry),
                                 w = validateModel(left, runs.val, {40}, carry);
    // When written, simulation as bending / steering: 95.6 / 76.4 taken out
    // against 93.5 / 75.3 left in. Steering stays low: the validation run's
    // own yaw drifts on.
    EXPECT_GT(v.outputs[0].fit_sim, w.outputs[0].fit_sim + 1.0);
    EXPECT_GT(v.outputs[1].fit_sim, w.outputs[1].fit_sim + 0.5);
    for (std::size_t i = 0; i < 2; ++i)
      EXPECT_GT(v.outputs[i].fit_k.at(40), w.outputs[i].fit_k.at(40) - 0.2) << v.outputs[i].name;
    // Registering the validation run's yaw without carrying the drift takes
    // the standing part of steering's error out of both, so the two are close
    // there (83.94 taken out, 83.73 left in, when written); bending cannot move.
    const eval::SimulationStart registered_only{5.0, false};
    const eval::ValidationResult vr = validateModel(taken, runs.val, {40}, registered_only),
                                 wr = validateModel(left, runs.val, {40}, registered_only);
    EXPECT_GT(vr.outputs[1].fit_sim, v.outputs[1].fit_sim + 5.0);
    EXPECT_GT(wr.outputs[1].fit_sim, w.outputs[1].fit_sim + 5.0);
    EXPECT_NEAR(vr.outputs[1].fit_sim, wr.outputs[1].fit_sim, 1.0);
    const Eigen::Index scored = runs.val.samples() - 400;  // after the 5 s registration window
    EXPECT_LT((vr.outputs[0].simulated.tail(scored) - v.outputs[0].simulated.tail(scored)).cwiseAbs().maxCoeff(), 1e-9);
    // By default the model that took the drift out turns at it over the new
    // run, whose sensor drifts on; the one that left it in has none to carry.
    const eval::ValidationResult vd = eval::validateModel(taken, runs.val, {40}),
                                 wd = eval::validateModel(left, runs.val, {40});
    EXPECT_GT(vd.outputs[1].fit_sim, vr.outputs[1].fit_sim + 5.0);
    EXPECT_EQ(wd.outputs[1].fit_sim, wr.outputs[1].fit_sim);
  }
  const DriftRuns still = yawDriftRuns(0.0);
  IdentifyReport rep;
  identifyModel({still.train}, fixedInputSide(OutputFrame::kTipCartesian), &rep);
  ASSERT_EQ(rep.output_drift.rate.size(), 2u);
  EXPECT_NEAR(rep.output_drift.rate[1], 0.0, 0.1 * rate);  // -0.00001 when written
  // Without a drift, taking one out gains less than its error (98.000 ->
  // 98.002, a gain of 0.002 +- 0.004 when written): left in, where any gain
  // would have taken it out.
  EXPECT_GT(rep.drift_scores.second, rep.drift_scores.first - 0.05);
  EXPECT_TRUE(std::isfinite(rep.drift_gain.second));  // scored: the terms paired
  EXPECT_LE(rep.drift_gain.first, rep.drift_gain.second);
  EXPECT_FALSE(rep.drift_taken_out);
}

TEST(Pipeline, DefaultOutputFrameIsChosenReportedAndOverridable) {
  const io::Log& train = allEffectsRuns().train;
  IdentifyOptions o;  // a cheap structure: the frame is what is checked
  o.scheduling = SchedulingChoice::kSwitched;
  o.play_candidates = {{0.0}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  o.slow_pole_candidates = {};
  o.play_threshold_candidates = {};
  IdentifyReport report;
  EXPECT_EQ(identifyModel({train}, o, &report).output_frame, OutputFrame::kTipCartesian);
  EXPECT_EQ(report.output_frame.frame, OutputFrame::kTipCartesian);
  const bool said = std::any_of(report.lines.begin(), report.lines.end(), [](const std::string& l) {
    return l.find("read as a tip's bending and steering angles") != std::string::npos;
  });
  EXPECT_TRUE(said) << "the choice is in the progress lines";
  o.output_frame = OutputFrame::kAsLogged;
  EXPECT_EQ(identifyModel({train}, o, &report).output_frame, OutputFrame::kAsLogged);
}

TEST(Pipeline, TipFrameLiftsTheKStepFits) {
  const io::Log& train = allEffectsRuns().train;
  const io::Log& val = allEffectsRuns().val;
  // The demo's structure, fixed so that only the frame differs.
  IdentifyOptions o;
  o.scheduling = SchedulingChoice::kInputSide;
  o.output_drift = OutputDriftChoice::kAuto;
  o.play_candidates = {{PlayChannel(0.0, 0.12)}};
  o.play_coupling_candidates = {0.3};
  o.schedule_lag_candidates = {0.8};
  o.slow_pole_candidates = {2.0};
  o.play_threshold_candidates = {};
  o.output_frame = OutputFrame::kAsLogged;
  const DioPwlObfModel logged = identifyModel({train}, o);
  o.output_frame = OutputFrame::kTipCartesian;
  const DioPwlObfModel tip = identifyModel({train}, o);
  EXPECT_EQ(tip.output_frame, OutputFrame::kTipCartesian);
  EXPECT_EQ(tip.outputs, logged.outputs);  // still named, and answered, as logged
  const eval::ValidationResult v = eval::validateModel(tip, val, {40, 80});
  const eval::ValidationResult w = eval::validateModel(logged, val, {40, 80});
  // When written: bending 94.1 / 92.3 / 86.9 against 92.2 / 88.5 / 87.4 as
  // logged; steering 95.7 / 94.2 / 87.9 against 95.0 / 93.0 / 87.5.
  // Simulation hardly moves (docs/identification.md).
  expectLifted(v, w, {92.0, 90.0, 78.0}, {0.3, 0.6});
}

// The simulator's chambers only stretch past 0.06 bar (its deadzone), and its
// play band and coupling act on the strain above it: counting the play
// channels from a threshold must be chosen, near that level, and lift the fits.
TEST(Pipeline, PlayThresholdIsChosenNearTheDeadzoneAndLiftsTheFits) {
  const io::Log& train = allEffectsRuns().train;
  const io::Log& val = allEffectsRuns().val;
  IdentifyOptions o;  // the demo's structure, two growing bands to choose from
  o.output_frame = OutputFrame::kTipCartesian;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{PlayChannel(0.0, 0.12)}, {PlayChannel(0.0, 0.16)}};
  o.play_coupling_candidates = {0.3};
  o.schedule_lag_candidates = {0.8};
  o.slow_pole_candidates = {2.0};
  o.output_drift = OutputDriftChoice::kAuto;  // as the demo asks, its sensor drifting
  o.play_threshold_candidates = {};
  const DioPwlObfModel from_zero = identifyModel({train}, o);
  EXPECT_EQ(from_zero.shaping.threshold, 0.0);
  const IdentifyOptions defaults;
  o.play_threshold_candidates = defaults.play_threshold_candidates;
  IdentifyReport rep;
  const DioPwlObfModel counted = identifyModel({train}, o, &rep);
  // Candidates 0.035, 0.07 and 0.105 bar (fractions of the 0.35 bar top level).
  EXPECT_NEAR(counted.shaping.threshold, 0.06, 0.015);
  ASSERT_FALSE(rep.threshold_scores.empty());
  EXPECT_EQ(rep.threshold_scores.front().threshold, 0.0);  // the model without, scored first
  const eval::ValidationResult v = eval::validateModel(counted, val, {40, 80});
  const eval::ValidationResult w = eval::validateModel(from_zero, val, {40, 80});
  // When written: bending 95.9 / 94.5 / 91.2 against 94.1 / 92.3 / 86.9 from
  // zero; steering 97.4 / 96.4 / 89.0 against 95.7 / 94.2 / 87.9.
  expectLifted(v, w, {94.5, 93.0, 85.0}, {0.8, 1.2});
  // The sensor's yaw drifts at 0.02 deg/s; the other effects bias the
  // estimate (0.0244 when written, 0.0047 with the sensor's bias off).
  EXPECT_TRUE(rep.drift_taken_out);
  ASSERT_EQ(rep.output_drift.rate.size(), 2u);
  EXPECT_NEAR(rep.output_drift.rate[1], 0.02, 0.008);
}

// The joint refinement starts from the staged choice and may only keep a
// point that scores higher on the held-out chunks, and simulates no worse on
// them, inside its box, within its budget. From a structure without a
// threshold it must find the simulator's deadzone (0.06 bar) from the score
// alone. It refines only the stages that ran, and only on the input side.
TEST(Pipeline, JointRefinementRaisesTheHeldOutScoreWithinItsBoxAndBudget) {
  const io::Log& train = allEffectsRuns().train;
  IdentifyOptions o;
  o.output_frame = OutputFrame::kTipCartesian;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{PlayChannel(0.0, 0.16)}};
  o.play_coupling_candidates = {0.3};
  o.schedule_lag_candidates = {};
  o.play_threshold_candidates = {0.0};  // the stages run, from zero and unsoftened
  o.play_softening_candidates = {0.0};
  o.play_refine_evaluations = 0;
  o.slow_pole_candidates = {};
  o.output_drift = OutputDriftChoice::kOff;
  IdentifyReport plain;
  const DioPwlObfModel staged = identifyModel({train}, o, &plain);
  EXPECT_EQ(plain.refine_evaluations, 0);
  EXPECT_EQ(staged.shaping.threshold, 0.0);
  EXPECT_EQ(staged.shaping.softening, 0.0);

  o.play_refine_evaluations = 14;
  IdentifyReport rep;
  const DioPwlObfModel refined = identifyModel({train}, o, &rep);
  EXPECT_GT(rep.refine_evaluations, 0);
  EXPECT_LE(rep.refine_evaluations, 14);
  EXPECT_EQ(rep.refine_start.threshold, 0.0);
  EXPECT_NEAR(rep.refine_start.coupling, 0.3, 1e-12);
  EXPECT_EQ(rep.refine_start.channel_scale, 1.0);
  const auto& b = rep.refine_best;
  std::printf("refined in %d scores: %.3f -> %.3f held out; threshold %.3f, coupling %.3f, softening %.3f, x%.3f\n",
              rep.refine_evaluations, rep.refine_start.score, b.score, b.threshold, b.coupling, b.softening,
              b.channel_scale);
  EXPECT_GT(b.score, rep.refine_start.score + 0.3) << "start " << rep.refine_start.score;
  EXPECT_GE(b.threshold, 0.0);
  EXPECT_LE(b.threshold, 0.45);
  EXPECT_LE(b.coupling, 0.6);
  EXPECT_LE(b.softening, 0.45);
  EXPECT_GE(b.channel_scale, 0.5);
  EXPECT_LE(b.channel_scale, 2.0);
  // The model carries the best point, in its own units (top level 0.35 bar).
  const double top = 0.35;
  EXPECT_NEAR(refined.shaping.threshold, b.threshold * top, 1e-9);
  EXPECT_NEAR(refined.shaping.coupling * (top - refined.shaping.threshold), b.coupling, 1e-9);
  EXPECT_NEAR(refined.shaping.softening * (top - refined.shaping.threshold), b.softening, 1e-9);
  ASSERT_EQ(refined.shaping.play.size(), 3u);
  EXPECT_NEAR(refined.shaping.play[0].at(0).slope, 0.16 * b.channel_scale, 1e-12);
  EXPECT_GT(refined.shaping.threshold, 0.02);
  EXPECT_LT(refined.shaping.threshold, 0.12);
  EXPECT_GT(rep.refine_simulation.first, 50.0) << "the staged choice's held-out simulation was not scored";
  EXPECT_GE(rep.refine_simulation.second, rep.refine_simulation.first);
  const bool said = std::any_of(rep.lines.begin(), rep.lines.end(),
                                [](const std::string& l) { return l.find("refined jointly") != std::string::npos; });
  EXPECT_TRUE(said);

  // A stage turned off keeps its setting: without threshold candidates the
  // threshold stays at zero while the rest is refined.
  o.play_threshold_candidates = {};
  IdentifyReport no_threshold;
  const DioPwlObfModel kept_zero = identifyModel({train}, o, &no_threshold);
  EXPECT_GT(no_threshold.refine_evaluations, 0);
  EXPECT_EQ(kept_zero.shaping.threshold, 0.0);
  EXPECT_EQ(no_threshold.refine_best.threshold, 0.0);
  // The output side has no held-out simulation to guard it: not refined.
  o.play_threshold_candidates = {0.0};
  o.scheduling = SchedulingChoice::kInterpolated;
  IdentifyReport output_side;
  identifyModel({train}, o, &output_side);
  EXPECT_EQ(output_side.refine_evaluations, 0);
  EXPECT_TRUE(std::any_of(output_side.lines.begin(), output_side.lines.end(), [](const std::string& l) {
    return l.find("input-side structures only") != std::string::npos;
  }));
  o.scheduling = SchedulingChoice::kInputSide;

  o.play_refine_evaluations = -1;
  EXPECT_THROW(
      {
        try {
          identifyModel({train}, o);
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("refinement evaluations"), std::string::npos) << e.what();
          throw;
        }
      },
      std::invalid_argument);
}

TEST(Pipeline, AllEffectsPlayModelBeatsThePapersConfiguration) {
  const io::Log& train = allEffectsRuns().train;
  const io::Log& val = allEffectsRuns().val;
  sim::ExperimentOptions eo;
  eo.seed = 2;
  IdentifyReport rep;
  const IdentifyOptions defaults;
  const DioPwlObfModel ours = identifyModel({train}, defaults, &rep);
  IdentifyOptions paper_options;
  paper_options.scheduling = SchedulingChoice::kSwitched;
  paper_options.play_candidates = {{0.0}};
  paper_options.play_bank_candidates = {};
  paper_options.play_coupling_candidates = {};
  const DioPwlObfModel paper = identifyModel({train}, paper_options);
  EXPECT_EQ(paper.shaping.coupling, 0.0);
  // Hysteresis that scales with the strain, on chambers that stiffen each
  // other: a growing, coupled band must be the choice.
  ASSERT_EQ(ours.shaping.play[0].size(), 1u);
  EXPECT_GT(ours.shaping.play[0][0].slope, 0.0);
  EXPECT_GT(ours.shaping.coupling, 0.0);
  const eval::ValidationResult v = eval::validateModel(ours, val, {40, 80});
  const eval::ValidationResult w = eval::validateModel(paper, val, {40, 80});
  // A run that starts before the creep has settled.
  eo.joystick_preroll_s = 5.0;
  sim::Actuator c(sim::SimConfig{}, 101);
  const eval::ValidationResult s = eval::validateModel(ours, sim::runExperiment(c, sim::joystickExperiment(eo)), {40});
  for (std::size_t o = 0; o < v.outputs.size(); ++o) {
    EXPECT_GT(v.outputs[o].fit_k.at(40), 90.0) << v.outputs[o].name;
    EXPECT_GT(v.outputs[o].fit_k.at(80), 86.0) << v.outputs[o].name;
    EXPECT_GT(v.outputs[o].fit_k.at(40), w.outputs[o].fit_k.at(40) + 8.0) << v.outputs[o].name;
    EXPECT_GT(v.outputs[o].fit_k.at(80), w.outputs[o].fit_k.at(80) + 15.0) << v.outputs[o].name;
    // Free simulation from the settled start (86.5 and 84.0 when written; the
    // paper's configuration drifts to 21 and 28).
    EXPECT_GT(v.outputs[o].fit_sim, 75.0) << v.outputs[o].name;
    EXPECT_GT(v.outputs[o].fit_sim, w.outputs[o].fit_sim + 40.0) << v.outputs[o].name;
    // Simulated from the model's level, an unsettled start costs little (80.3
    // and 81.2 when written; from the first sample, bending fell to 37).
    EXPECT_GT(s.outputs[o].fit_sim, 70.0) << v.outputs[o].name;
  }
}
