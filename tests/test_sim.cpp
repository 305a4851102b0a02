#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "plsa/sim/actuator.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/independent_actuator.hpp"

using namespace plsa::sim;

namespace {

SimConfig allOff() {
  SimConfig c;
  for (const auto& e : effectNames()) c.setEffectEnabled(e, false);
  c.sensor.noise_deg = 0.0;
  return c;
}

SimConfig only(const std::string& effect) {
  SimConfig c = allOff();
  c.setEffectEnabled(effect, true);
  return c;
}

// Holds a command for `seconds`, returns the samples.
std::vector<ActuatorSample> hold(Actuator& a, std::array<double, 3> cmd, double seconds) {
  std::vector<ActuatorSample> out;
  const int n = static_cast<int>(std::lround(seconds * a.config().sample_rate_hz));
  for (int k = 0; k < n; ++k) out.push_back(a.step(cmd));
  return out;
}

double settled(Actuator& a, std::array<double, 3> cmd, double seconds = 5.0) {
  return hold(a, cmd, seconds).back().true_bend_deg;
}

// 10-90% rise time of a local step response, judged against the bend 1.5 s
// after the step (the local response; creep keeps drifting after that).
double riseTime(Actuator& a, double from, double to) {
  const double start = settled(a, {from, 0, 0}, 8.0);
  const auto r = hold(a, {to, 0, 0}, 1.5);
  const double end = r.back().true_bend_deg;
  int t10 = -1, t90 = -1;
  for (int k = 0; k < static_cast<int>(r.size()); ++k) {
    const double frac = (r[static_cast<std::size_t>(k)].true_bend_deg - start) / (end - start);
    if (t10 < 0 && frac >= 0.1) t10 = k;
    if (t90 < 0 && frac >= 0.9) t90 = k;
  }
  return (t90 - t10) / a.config().sample_rate_hz;
}

// Up and down staircase on chamber 1; bend settled at `probe` bar on each way.
std::pair<double, double> upDownAt(const SimConfig& c, double probe) {
  Actuator a(c, 1);
  double up = 0, down = 0;
  for (int k = 1; k <= 14; ++k) {
    const double p = 0.025 * k;
    const double b = settled(a, {p, 0, 0}, 4.0);
    if (std::abs(p - probe) < 1e-9) up = b;
  }
  for (int k = 13; k >= 0; --k) {
    const double p = 0.025 * k;
    const double b = settled(a, {p, 0, 0}, 4.0);
    if (std::abs(p - probe) < 1e-9) down = b;
  }
  return {up, down};
}

}  // namespace

// --- what the paper's Fig. 3 shows, in the default configuration -----------

TEST(SimFig3, DeadzoneAtLowPressure) {
  SimConfig c;
  Actuator a(c, 1);
  EXPECT_LT(settled(a, {0.04, 0, 0}), 0.2);
  EXPECT_GT(settled(a, {0.12, 0, 0}), 5.0);
}

TEST(SimFig3, NonlinearSteadyState) {
  Actuator a(SimConfig{}, 1);
  const double b10 = settled(a, {0.10, 0, 0}), b15 = settled(a, {0.15, 0, 0});
  const double b30 = settled(a, {0.30, 0, 0}), b35 = settled(a, {0.35, 0, 0});
  const double low_gain = (b15 - b10) / 0.05, high_gain = (b35 - b30) / 0.05;
  EXPECT_GT(low_gain, 1.3 * high_gain) << low_gain << " vs " << high_gain << " deg/bar";
}

TEST(SimFig3, HysteresisLoopBetweenIncreaseAndDecrease) {
  const auto [up, down] = upDownAt(SimConfig{}, 0.2);
  EXPECT_GT(down - up, 3.0) << "up " << up << " down " << down;
}

TEST(SimFig3, SteeperLocalStepsAtHigherPressure) {
  Actuator a(SimConfig{}, 1);
  const double low = riseTime(a, 0.10, 0.125);
  const double high = riseTime(a, 0.30, 0.325);
  EXPECT_LT(high, 0.8 * low) << "rise time " << low << " s at low, " << high << " s at high pressure";
}

// --- each effect: its signature with it on, gone with it off ---------------

TEST(SimEffects, Deadzone) {
  for (const std::string f : {"sharp", "smooth"}) {
    SimConfig on = only("deadzone");
    on.deadzone.formulation = f;
    Actuator a(on, 1), b(allOff(), 1);
    EXPECT_LT(settled(a, {0.03, 0, 0}), 0.5) << f;
    EXPECT_GT(settled(b, {0.03, 0, 0}), 4.0);
  }
}

TEST(SimEffects, Hysteresis) {
  for (const std::string f : {"play", "prandtl_ishlinskii"}) {
    SimConfig on = only("hysteresis");
    on.hysteresis.formulation = f;
    const auto [up, down] = upDownAt(on, 0.2);
    EXPECT_GT(down - up, 3.0) << f;
  }
  const auto [up, down] = upDownAt(allOff(), 0.2);
  EXPECT_LT(std::abs(down - up), 0.05);
}

TEST(SimEffects, Stiffening) {
  Actuator on(only("stiffening"), 1), off(allOff(), 1);
  EXPECT_LT(riseTime(on, 0.30, 0.325), 0.75 * riseTime(on, 0.05, 0.075));
  const double ratio = riseTime(off, 0.30, 0.325) / riseTime(off, 0.05, 0.075);
  EXPECT_NEAR(ratio, 1.0, 0.05);
}

TEST(SimEffects, CouplingBreaksSuperposition) {
  auto gap = [](const SimConfig& c) {
    auto vec = [&](std::array<double, 3> cmd) {
      Actuator a(c, 1);
      const auto s = hold(a, cmd, 6.0).back();
      const double t = s.true_bend_deg, p = s.true_steer_deg * M_PI / 180;
      return Eigen::Vector2d(t * std::cos(p), t * std::sin(p));
    };
    return (vec({0.25, 0.25, 0}) - vec({0.25, 0, 0}) - vec({0, 0.25, 0})).norm();
  };
  EXPECT_GT(gap(only("coupling")), 3.0);
  EXPECT_LT(gap(allOff()), 0.05);
}

TEST(SimEffects, PneumaticLagFillsSlowerThanVentAfterADelay) {
  auto times = [](const SimConfig& c) {
    Actuator a(c, 1);
    const auto fill = hold(a, {0.3, 0, 0}, 3.0);
    const auto vent = hold(a, {0.0, 0, 0}, 3.0);
    // Counted from the first sample the pressure moves, so the delay is not in it.
    int f0 = 0, tf = 0, v0 = 0, tv = 0;
    while (fill[static_cast<std::size_t>(f0)].pressure_bar[0] == 0.0) ++f0;
    while (fill[static_cast<std::size_t>(tf)].pressure_bar[0] < 0.3 * 0.63) ++tf;
    while (vent[static_cast<std::size_t>(v0)].pressure_bar[0] >= fill.back().pressure_bar[0]) ++v0;
    while (vent[static_cast<std::size_t>(tv)].pressure_bar[0] > 0.3 * 0.37) ++tv;
    return std::tuple{tf - f0, tv - v0, fill[0].pressure_bar[0]};
  };
  const auto [tf_on, tv_on, first_on] = times(only("pneumatic_lag"));
  EXPECT_GT(tf_on, 2 * tv_on);
  EXPECT_EQ(first_on, 0.0);  // 30 ms transport delay: nothing in the first 12.5 ms sample
  const auto [tf_off, tv_off, first_off] = times(allOff());
  EXPECT_LE(std::abs(tf_off - tv_off), 1);
  EXPECT_GT(first_off, 0.0);
}

TEST(SimEffects, CreepDriftsUnderConstantPressure) {
  auto drift = [](const SimConfig& c) {
    Actuator a(c, 1);
    const auto r = hold(a, {0.3, 0, 0}, 30.0);
    return r.back().true_bend_deg - r[5 * 80].true_bend_deg;
  };
  EXPECT_GT(drift(only("creep")), 2.0);
  EXPECT_LT(std::abs(drift(allOff())), 0.01);
}

TEST(SimEffects, SensorBiasOffsetsAndDrifts) {
  Actuator on(only("sensor_bias"), 1), off(allOff(), 1);
  const auto s_on = hold(on, {0, 0, 0}, 1.0).back();
  EXPECT_NEAR(s_on.bend_deg, on.config().sensor_bias.tilt_deg, 0.05);
  EXPECT_NEAR(hold(off, {0, 0, 0}, 1.0).back().bend_deg, 0.0, 1e-6);
  // Yaw drift moves the measured steering while the tip holds still.
  Actuator d(only("sensor_bias"), 1);
  const auto r = hold(d, {0.3, 0, 0}, 40.0);
  const double moved = r.back().steer_deg - r[10 * 80].steer_deg;
  EXPECT_NEAR(moved, 30.0 * d.config().sensor_bias.yaw_drift_deg_per_s, 0.1);
  EXPECT_NEAR(r.back().true_steer_deg, r[10 * 80].true_steer_deg, 1e-9);
}

// --- kinematics and sensor equations -----------------------------------------

TEST(SimKinematics, SensorEquationsRecoverBendAndSteer) {
  for (double theta : {5.0, 45.0, 100.0})
    for (double phi : {-150.0, -10.0, 30.0, 170.0}) {
      const double t = theta * M_PI / 180, p = phi * M_PI / 180;
      const Eigen::Matrix3d g_r_tip = Eigen::AngleAxisd(p, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                                      Eigen::AngleAxisd(t, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                                      Eigen::AngleAxisd(-p, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const Eigen::Matrix3d g_r_b =
          g_r_tip * Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
      double bend, steer;
      anglesFromRotation(g_r_b.transpose(), bend, steer);
      EXPECT_NEAR(bend, theta, 1e-9);
      EXPECT_NEAR(steer, phi, 1e-9);
    }
}

TEST(SimKinematics, TipPositionIsWebsterJonesArc) {
  const double l = 0.09;
  const Eigen::Vector3d straight = tipPosition(l, 0.0, 0.3);
  EXPECT_NEAR(straight.z(), l, 1e-15);
  const Eigen::Vector3d quarter = tipPosition(l, M_PI / 2, 0.0);  // quarter circle, radius l/(pi/2)
  const double r = l / (M_PI / 2);
  EXPECT_NEAR(quarter.x(), r, 1e-12);
  EXPECT_NEAR(quarter.z(), r, 1e-12);
}

TEST(SimKinematics, SingleChamberBendsTowardItsDirectionAndSubspaces) {
  SimConfig c = allOff();
  for (int ch = 0; ch < 3; ++ch) {
    Actuator a(c, 1);
    std::array<double, 3> cmd{0, 0, 0};
    cmd[static_cast<std::size_t>(ch)] = 0.3;
    const auto s = hold(a, cmd, 5.0).back();
    const double want = c.geometry.bend_direction_deg[static_cast<std::size_t>(ch)];
    EXPECT_NEAR(std::remainder(s.steer_deg - want, 360.0), 0.0, 1e-6);
  }
  Actuator a(c, 1);
  const auto s = hold(a, {0.3, 0.3, 0}, 5.0).back();
  const Subspace sub = configurationSubspace(c.geometry, s.steer_deg);
  EXPECT_EQ(sub.index, 1);
  EXPECT_NEAR(sub.angle_deg, 60.0, 1e-6);
  EXPECT_EQ(configurationSubspace(c.geometry, 180.0).index, 2);
  EXPECT_EQ(configurationSubspace(c.geometry, -60.0).index, 3);
}

// --- configuration, input checks, determinism ----------------------------------

TEST(SimConfig, JsonRoundTripAndErrors) {
  SimConfig c;
  c.creep.enabled = false;
  c.hysteresis.formulation = "prandtl_ishlinskii";
  c.coupling.per_bar = 0.5;
  const SimConfig back = simConfigFromJson(simConfigToJson(c));
  EXPECT_FALSE(back.creep.enabled);
  EXPECT_EQ(back.hysteresis.formulation, "prandtl_ishlinskii");
  EXPECT_EQ(back.coupling.per_bar, 0.5);
  auto error = [](const std::string& text) {
    try {
      simConfigFromJson(text, "cfg.json");
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(error(R"({"creep": {"fraktion": 0.1}})").find("unknown key 'creep.fraktion'"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"fraction": 3}})").find("creep.fraction = 3 is outside"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"enabled": "yes"}})").find("true or false"), std::string::npos);
  EXPECT_NE(error(R"({"deadzone": {"formulation": "round"}})").find("formulation 'round'"), std::string::npos);
  EXPECT_NE(error(R"({"bogus": {}})").find("unknown section 'bogus'"), std::string::npos);
  EXPECT_NE(error("{").find("not valid JSON"), std::string::npos);
  // A number beyond double range escaped as a raw library exception; a key given twice kept the last.
  EXPECT_NE(error(R"({"sample_rate_hz": 1e400})").find("cfg.json: not valid JSON"), std::string::npos);
  EXPECT_NE(error(R"({"creep": {"fraction": 0.1, "fraction": 0.2}})").find("key 'creep.fraction' is given twice"),
            std::string::npos);
  EXPECT_NE(error(R"({"geometry": {"bend_direction_deg": [0, null, 240]}})").find("must be a number"), std::string::npos);
  // 0.75 p - 1 p^2 peaks at 0.375 bar, inside the 0.4 bar range; -0.9 peaks beyond it.
  EXPECT_NE(error(R"({"elongation": {"quadratic": -1.0}})").find("stops rising at 0.375 bar"), std::string::npos);
  EXPECT_EQ(error(R"({"elongation": {"quadratic": -0.9}})"), "accepted");
  EXPECT_EQ(error(R"({"elongation": {"quadratic": -1.0}, "max_pressure_bar": 0.35})"), "accepted");
}

TEST(SimConfig, ParametersAreAddressableByModule) {
  SimConfig c;
  auto p = c.parameters("pneumatic_lag");
  ASSERT_EQ(p.size(), 3u);
  *p[2].value = 0.07;
  EXPECT_EQ(c.pneumatic_lag.delay_s, 0.07);
  EXPECT_GE(c.parameters("nominal").size(), 6u);
  EXPECT_THROW(c.parameters("friction"), std::invalid_argument);
}

TEST(SimActuator, ClampsCommandsAndRejectsNaN) {
  Actuator a(SimConfig{}, 1);
  const auto s = a.step({0.9, -0.2, 0.1});
  EXPECT_EQ(s.command_bar[0], 0.4);
  EXPECT_EQ(s.command_bar[1], 0.0);
  EXPECT_THROW(a.step({std::nan(""), 0, 0}), std::invalid_argument);
}

// Free simulation starts from a steady state, so the validation run must:
// creep (8 s) left unsettled by a short pre-roll would read as model error.
TEST(SimExperiments, JoystickRunStartsSettled) {
  ExperimentOptions o;
  o.joystick_duration_s = 1.0;
  const Experiment joy = joystickExperiment(o);
  auto trueBendAfter = [&](Eigen::Index rows, double extra_hold_s) {
    Actuator a(SimConfig{}, 7);
    ActuatorSample s;
    std::array<double, 3> cmd{};
    for (Eigen::Index k = 0; k < rows; ++k) {
      for (int c = 0; c < 3; ++c) cmd[static_cast<std::size_t>(c)] = joy.commands(k, c);
      s = a.step(cmd);
    }
    for (int k = 0; k < static_cast<int>(extra_hold_s * o.sample_rate_hz); ++k) s = a.step(cmd);
    return s.true_bend_deg;
  };
  const double at_start = trueBendAfter(joy.record_from, 0.0);
  const double settled = trueBendAfter(joy.record_from, 200.0);
  ASSERT_GT(settled, 10.0);
  EXPECT_NEAR(at_start, settled, 0.1);
  // The grid's 5 s pre-roll would leave about 2 degrees of creep to come.
  EXPECT_GT(settled - trueBendAfter(static_cast<Eigen::Index>(o.preroll_s * o.sample_rate_hz), 0.0), 1.0);
}

TEST(SimExperiments, ShapesAndDeterminism) {
  ExperimentOptions o;
  const Experiment st = staircaseExperiment(o);
  EXPECT_EQ(st.commands.rows(), static_cast<Eigen::Index>((2.0 + 28 * 4.0) * 80));
  EXPECT_DOUBLE_EQ(st.commands.col(0).maxCoeff(), 0.35);
  const Experiment grid = gridExperiment(o);
  // One input moves at a time.
  EXPECT_GT(grid.record_from, 0);
  EXPECT_EQ(grid.commands(grid.record_from, 0), 0.20);
  for (Eigen::Index k = grid.record_from + 1; k < grid.commands.rows(); ++k)
    EXPECT_LE((grid.commands.row(k).array() != grid.commands.row(k - 1).array()).count(), 1);
  const Experiment joy = joystickExperiment(o);
  EXPECT_LE(joy.commands.maxCoeff(), o.joystick_max_bar + 1e-12);
  EXPECT_GE(joy.commands.bottomRows(joy.commands.rows() - joy.record_from).leftCols(2).minCoeff(),
            o.joystick_min_bar - 1e-12);
  o.joystick_duration_s = 10;
  auto run = [&](std::uint64_t seed) {
    o.seed = seed;
    Actuator a(SimConfig{}, seed);
    return runExperiment(a, joystickExperiment(o)).data;
  };
  EXPECT_EQ(run(3), run(3));
  EXPECT_NE(run(3), run(4));
  EXPECT_THROW(makeExperiment("sine", o), std::invalid_argument);
}

// Both chambers step together from the base to every point of the map, once,
// and come back to the base between points; the third chamber stays empty.
TEST(SimExperiments, StaticMapVisitsEveryPointOnceFromTheBase) {
  ExperimentOptions o;
  o.static_map_points = 3;
  const Experiment e = staticMapExperiment(o);
  const auto rate = static_cast<Eigen::Index>(o.sample_rate_hz);
  ASSERT_EQ(e.commands.rows() - e.record_from, 9 * (10 + 40) * rate);
  EXPECT_EQ(e.commands.col(2).cwiseAbs().maxCoeff(), 0.0);
  std::set<std::pair<double, double>> points;
  for (int p = 0; p < 9; ++p) {
    const Eigen::Index base = e.record_from + p * 50 * rate, at = base + 10 * rate;
    for (Eigen::Index k = base; k < at; ++k) {
      ASSERT_EQ(e.commands(k, 0), 0.19);
      ASSERT_EQ(e.commands(k, 1), 0.19);
    }
    for (Eigen::Index k = at; k < at + 40 * rate; ++k) ASSERT_EQ(e.commands.row(k), e.commands.row(at));
    points.insert({e.commands(at, 0), e.commands(at, 1)});
  }
  const std::set<std::pair<double, double>> expected = {
      {0.20, 0.20}, {0.20, 0.275}, {0.20, 0.35}, {0.275, 0.20}, {0.275, 0.275},
      {0.275, 0.35}, {0.35, 0.20}, {0.35, 0.275}, {0.35, 0.35}};
  ASSERT_EQ(points.size(), 9u);
  for (const auto& [pa, pb] : expected) {
    bool found = false;
    for (const auto& [qa, qb] : points) found = found || (std::abs(pa - qa) < 1e-12 && std::abs(pb - qb) < 1e-12);
    EXPECT_TRUE(found) << pa << ", " << pb;
  }
  EXPECT_EQ(makeExperiment("static_map", o).commands, e.commands);
}

// The grid exactly, then every diagonal step of its levels (both chambers a
// level up or down at once, in the same or opposite directions) exactly once
// each way; the third chamber stays empty.
TEST(SimExperiments, GridJointAddsEveryDiagonalStepOnceEachWay) {
  ExperimentOptions o;
  const Experiment grid = gridExperiment(o);
  const Experiment joint = gridJointExperiment(o);
  ASSERT_GT(joint.commands.rows(), grid.commands.rows());
  EXPECT_EQ(joint.record_from, grid.record_from);
  EXPECT_EQ(joint.commands.topRows(grid.commands.rows()), grid.commands);
  EXPECT_EQ(joint.commands.col(2).cwiseAbs().maxCoeff(), 0.0);
  const auto& L = o.grid_levels_bar;
  const auto level = [&](double bar) {
    for (std::size_t i = 0; i < L.size(); ++i)
      if (bar == L[i]) return static_cast<int>(i);
    ADD_FAILURE() << bar << " bar is not a grid level";
    return -100;
  };
  std::map<std::array<int, 4>, int> diagonal_moves;
  const auto hold = static_cast<Eigen::Index>(o.hold_s * o.sample_rate_hz);
  Eigen::Index since_change = hold;
  for (Eigen::Index k = grid.commands.rows(); k < joint.commands.rows(); ++k) {
    const int ia = level(joint.commands(k - 1, 0)), ja = level(joint.commands(k - 1, 1));
    const int ib = level(joint.commands(k, 0)), jb = level(joint.commands(k, 1));
    if (ia == ib && ja == jb) {
      ++since_change;
      continue;
    }
    EXPECT_EQ(since_change, hold) << "sample " << k;  // each point held hold_s
    since_change = 1;
    if (std::abs(ib - ia) == 1 && std::abs(jb - ja) == 1) ++diagonal_moves[{ia, ja, ib, jb}];
  }
  EXPECT_EQ(since_change, hold);
  const int n = static_cast<int>(L.size());
  ASSERT_EQ(diagonal_moves.size(), static_cast<std::size_t>(4 * (n - 1) * (n - 1)));
  for (const auto& [move, count] : diagonal_moves) {
    EXPECT_EQ(count, 1) << move[0] << "," << move[1] << " -> " << move[2] << "," << move[3];
    EXPECT_TRUE(move[0] >= 0 && move[0] < n && move[1] >= 0 && move[1] < n);
  }
  EXPECT_EQ(makeExperiment("grid2_joint", o).commands, joint.commands);
}

// Each time option is checked before it sizes anything: lround of an infinite
// hold is undefined, and a zero bandwidth divided by zero in the joystick's filter.
TEST(SimExperiments, RefusesTimesThatCannotBeBuiltByName) {
  const auto expectRefusal = [](const std::string& name, ExperimentOptions o, const std::string& words) {
    try {
      makeExperiment(name, o);
      ADD_FAILURE() << name << " accepted; expected '" << words << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  ExperimentOptions o;
  o.hold_s = std::numeric_limits<double>::infinity();
  expectRefusal("grid2", o, "hold_s must be a finite number above 0");
  o = {};
  o.preroll_s = std::nan("");
  expectRefusal("grid2", o, "preroll_s must be a finite number >= 0");
  o = {};
  o.joystick_bandwidth_hz = 0;
  expectRefusal("joystick", o, "joystick_bandwidth_hz must be above 0 and at most half the sample rate");
  o = {};
  o.hold_s = 1e6;  // 28 holds: 2.8e7 s
  expectRefusal("staircase1", o, "above the 10000000 one experiment holds");
  o = {};
  o.sample_rate_hz = 1e6;  // the default 60 s joystick, at a rate no rig samples at
  expectRefusal("joystick", o, "joystick: 101 s at 1e+06 Hz is 1.01e+08 samples");
  o = {};
  o.static_map_hold_s = std::numeric_limits<double>::infinity();
  expectRefusal("static_map", o, "static_map_hold_s must be a finite number above 0");
  o = {};
  o.static_map_points = 1;
  expectRefusal("static_map", o, "static_map_points must be 2 to 100");
  o = {};
  o.static_map_base_bar = 0.25;
  expectRefusal("static_map", o, "the base must not be above the grid's lowest level");
  o = {};
  o.static_map_points = 100;  // 10000 points of 50 s at 80 Hz
  expectRefusal("static_map", o, "above the 10000000 one experiment holds");
}

TEST(SimEffects, EveryEffectHasAnotherFormulationThatKeepsItsSignatureButDiffers) {
  // What the diagnosis self-check generates "real" data with: the same
  // phenomenon, a different law. Each alternative must differ from the
  // default and still show the effect's signature.
  for (const auto& e : effectNames()) {
    const auto& forms = formulationsOf(e);
    ASSERT_GE(forms.size(), 2u) << e;
    for (std::size_t f = 1; f < forms.size(); ++f) {
      SimConfig a = only(e), b = only(e);
      EXPECT_EQ(a.formulationOf(e), forms[0]) << e << ": the default comes first";
      b.formulationOf(e) = forms[f];
      if (forms[f] == "weighted_pi") b.hysteresis.weight_wide = 0.5;  // its defaults are the play's
      Actuator x(a, 1), y(b, 1), off(allOff(), 1);
      double differs = 0.0, effect = 0.0;
      for (std::array<double, 3> cmd : {std::array<double, 3>{0.05, 0, 0}, {0.3, 0.2, 0}, {0.15, 0, 0.25}, {0, 0, 0.1}}) {
        const auto rx = hold(x, cmd, 4.0), ry = hold(y, cmd, 4.0), ro = hold(off, cmd, 4.0);
        // Measured bending vector and chamber pressure: every effect shows in one of them.
        auto v = [](const ActuatorSample& s) {
          const double p = s.steer_deg * M_PI / 180;
          return Eigen::Vector3d(s.bend_deg * std::cos(p), s.bend_deg * std::sin(p), 100.0 * s.pressure_bar[0]);
        };
        for (std::size_t k = 0; k < rx.size(); ++k) {
          differs = std::max(differs, (v(rx[k]) - v(ry[k])).norm());
          effect = std::max(effect, (v(ry[k]) - v(ro[k])).norm());
          ASSERT_TRUE(std::isfinite(ry[k].bend_deg)) << e << " " << forms[f];
        }
      }
      EXPECT_GT(differs, 1e-3) << e << ": " << forms[f] << " behaves exactly like " << forms[0];
      EXPECT_GT(effect, 0.05) << e << ": " << forms[f] << " shows no effect at all";
    }
  }
  SimConfig bad;
  bad.creep.formulation = "logarithmic";
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// The diagnosis's flexible laws must contain the fixed ones they generalise:
// power stiffening at exponents 1 and 2 is linear and quadratic; power flow at
// 0.5 and 1 is orifice and linear. Same runs, sample for sample (to rounding:
// the laws are written differently, and the square root's infinite gain at a
// zero difference magnifies it).
TEST(SimEffects, PowerLawsReduceToTheFixedOnes) {
  struct Case {
    std::string effect, fixed;
    double exponent;
  };
  for (const Case& c : {Case{"stiffening", "linear", 1.0}, Case{"stiffening", "quadratic", 2.0},
                        Case{"pneumatic_lag", "linear", 1.0}, Case{"pneumatic_lag", "orifice", 0.5}}) {
    SimConfig a = only(c.effect), b = only(c.effect);
    a.formulationOf(c.effect) = c.fixed;
    b.formulationOf(c.effect) = "power";
    (c.effect == "stiffening" ? b.stiffening.exponent : b.pneumatic_lag.exponent) = c.exponent;
    Actuator x(a, 1), y(b, 1);
    for (std::array<double, 3> cmd : {std::array<double, 3>{0.3, 0.2, 0}, {0.05, 0, 0.35}}) {
      const auto rx = hold(x, cmd, 2.0), ry = hold(y, cmd, 2.0);
      for (std::size_t k = 0; k < rx.size(); ++k) {
        ASSERT_NEAR(rx[k].bend_deg, ry[k].bend_deg, 1e-4) << c.effect << " " << c.fixed << " k=" << k;
        ASSERT_NEAR(rx[k].pressure_bar[0], ry[k].pressure_bar[0], 1e-6) << c.effect << " " << c.fixed;
      }
    }
  }
}

TEST(SimEffects, StiffeningsStaticShareHoldsTheBendBack) {
  SimConfig dynamic = only("stiffening");
  dynamic.stiffening.formulation = "power";
  SimConfig hardening = dynamic;
  hardening.stiffening.static_share = 1.0;
  Actuator a(dynamic, 1), b(hardening, 1), off(allOff(), 1);
  const double low_a = settled(a, {0.04, 0, 0}, 6.0), low_b = settled(b, {0.04, 0, 0}, 6.0);
  const double high_a = settled(a, {0.35, 0, 0}, 6.0), high_b = settled(b, {0.35, 0, 0}, 6.0);
  const double high_off = settled(off, {0.35, 0, 0}, 6.0);
  EXPECT_NEAR(high_a, high_off, 0.01 * high_off);  // share 0: the same static bend, only sooner
  EXPECT_LT(high_b, 0.6 * high_a);                 // share 1: held back by the stiffer spring
  EXPECT_GT(low_b / low_a, 2.0 * high_b / high_a);  // far less held back at low pressure
}

TEST(SimEffects, WeightedPrandtlIshlinskiiContainsThePlayAndNoHysteresis) {
  SimConfig play = only("hysteresis"), pi = only("hysteresis"), none = allOff();
  pi.hysteresis.formulation = "weighted_pi";
  pi.hysteresis.weight_narrow = pi.hysteresis.weight_wide = 0.0;
  pi.hysteresis.weight_mid = 1.0;
  SimConfig flat = pi;
  flat.hysteresis.weight_mid = 0.0;
  SimConfig spread = pi;
  spread.hysteresis.weight_narrow = spread.hysteresis.weight_wide = 0.5;
  spread.hysteresis.weight_mid = 0.5;  // sums to 1.5: scaled to 1
  Actuator a(play, 1), b(pi, 1), c(none, 1), d(flat, 1), e(spread, 1);
  double differs = 0.0;
  for (std::array<double, 3> cmd : {std::array<double, 3>{0.3, 0.1, 0}, {0.1, 0, 0.2}, {0.35, 0.3, 0}}) {
    const auto ra = hold(a, cmd, 2.0), rb = hold(b, cmd, 2.0), rc = hold(c, cmd, 2.0), rd = hold(d, cmd, 2.0),
               re = hold(e, cmd, 2.0);
    for (std::size_t k = 0; k < ra.size(); ++k) {
      ASSERT_NEAR(ra[k].bend_deg, rb[k].bend_deg, 1e-9);
      ASSERT_NEAR(rc[k].bend_deg, rd[k].bend_deg, 1e-9);
      ASSERT_TRUE(std::isfinite(re[k].bend_deg));
      differs = std::max(differs, std::abs(re[k].bend_deg - ra[k].bend_deg));
    }
  }
  EXPECT_GT(differs, 0.05);  // other weights give another loop
  EXPECT_EQ(flexibleFormulationOf("hysteresis"), "weighted_pi");
  EXPECT_EQ(pi.parameters("hysteresis").size(), 4u);
}

TEST(SimEffects, SensorOffsetAndDriftMoveTheBendingVector) {
  SimConfig c = only("sensor_bias");
  c.sensor_bias.tilt_deg = c.sensor_bias.yaw_drift_deg_per_s = 0.0;
  SimConfig biased = c;
  biased.sensor_bias.offset_x_deg = 1.0;
  biased.sensor_bias.drift_y_deg_per_s = 0.1;
  Actuator a(c, 1), b(biased, 1);
  const auto ra = hold(a, {0.2, 0.1, 0}, 10.0), rb = hold(b, {0.2, 0.1, 0}, 10.0);
  auto vec = [](const ActuatorSample& s) {
    return Eigen::Vector2d(s.bend_deg * std::cos(s.steer_deg * M_PI / 180), s.bend_deg * std::sin(s.steer_deg * M_PI / 180));
  };
  for (std::size_t k : {std::size_t{79}, std::size_t{799}}) {
    const Eigen::Vector2d d = vec(rb[k]) - vec(ra[k]);
    EXPECT_NEAR(d.x(), 1.0, 1e-9);
    EXPECT_NEAR(d.y(), 0.1 * rb[k].time_s, 1e-9);
  }
}

// --- the independently written actuator (the self-check's "real" data) -----

namespace {

std::vector<IndependentSample> holdIndependent(IndependentActuator& a, std::array<double, 3> cmd, double seconds) {
  std::vector<IndependentSample> out;
  for (int k = 0; k < static_cast<int>(std::lround(seconds * 80.0)); ++k) out.push_back(a.step(cmd));
  return out;
}

IndependentPhysics quietIndependent() {
  IndependentPhysics p;
  p.noise_deg = 0.0;
  p.pressure_noise_bar = 0.0;
  return p;
}

}  // namespace

TEST(IndependentActuator, StartsAtRestAndBendsTowardTheChamber) {
  IndependentActuator a(quietIndependent(), 1);
  const IndependentSample first = a.step({0.3, 0, 0});
  EXPECT_LT(first.bending_deg.norm(), 0.5);  // vented and straight when recording begins
  EXPECT_LT(first.pressure_bar[0], 0.1);
  const auto r = holdIndependent(a, {0.3, 0, 0}, 6.0);
  EXPECT_NEAR(r.back().pressure_bar[0], 0.3, 0.01);
  EXPECT_GT(r.back().bending_deg.x(), 5.0);
  EXPECT_NEAR(r.back().bending_deg.y(), 0.0, 0.05 * r.back().bending_deg.x());
}

TEST(IndependentActuator, EveryLawChangesTheResponseAndEachDiffersFromTheOthers) {
  for (const std::string& effect : effectNames()) {
    const auto& laws = independentLawsOf(effect);
    ASSERT_GE(laws.size(), 3u) << effect;
    // A staircase up and down on two chambers: every law shows on it.
    const std::map<std::string, double> strength = {{"deadzone", 0.06}, {"hysteresis", 0.15}, {"stiffening", 1.0},
                                                    {"coupling", 0.8},  {"pneumatic_lag", 0.3}, {"creep", 0.1},
                                                    {"sensor_bias", 1.5}};
    auto response = [&](const std::string& law) {
      IndependentPhysics p = quietIndependent();
      if (!law.empty()) setIndependentEffect(p, effect, law, strength.at(effect));
      IndependentActuator a(p, 7);
      std::vector<double> trace;
      for (double c : {0.1, 0.25, 0.35, 0.2, 0.05, 0.0})
        for (const auto& s : holdIndependent(a, {c, 0.5 * c, 0}, 3.0)) {
          trace.push_back(s.bending_deg.x());
          trace.push_back(s.bending_deg.y());
        }
      return Eigen::Map<Eigen::VectorXd>(trace.data(), static_cast<Eigen::Index>(trace.size())).eval();
    };
    const Eigen::VectorXd off = response("");
    std::vector<Eigen::VectorXd> each;
    for (const auto& law : laws) {
      each.push_back(response(law));
      EXPECT_GT((each.back() - off).cwiseAbs().maxCoeff(), 0.2) << effect << " / " << law << " changes nothing";
    }
    for (std::size_t i = 0; i < each.size(); ++i)
      for (std::size_t j = i + 1; j < each.size(); ++j)
        EXPECT_GT((each[i] - each[j]).cwiseAbs().maxCoeff(), 0.05) << effect << ": " << laws[i] << " = " << laws[j];
  }
}

TEST(IndependentActuator, RejectsUnknownLawsValuesAndCommands) {
  IndependentPhysics p;
  EXPECT_THROW(setIndependentEffect(p, "friction", "coulomb", 1.0), std::invalid_argument);
  EXPECT_THROW(setIndependentEffect(p, "creep", "maxwell", 1.0), std::invalid_argument);
  p.hysteresis = "play";  // plsa's own law is not one of the independent ones
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = IndependentPhysics{};
  p.natural_freq_hz = -1.0;
  EXPECT_THROW(IndependentActuator(p, 1), std::invalid_argument);
  IndependentActuator a(IndependentPhysics{}, 1);
  EXPECT_THROW(a.step({std::nan(""), 0, 0}), std::invalid_argument);
}
