// The experiments the simulator runs (grid, static map, joystick): their
// shapes, determinism, starts and refusals.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "plsa/sim/actuator.hpp"
#include "plsa/sim/experiment.hpp"
#include "support/sim_probes.hpp"

using namespace plsa::sim;
using namespace plsa::sim::probes;

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
  const std::set<std::pair<double, double>> expected = {{0.20, 0.20},  {0.20, 0.275},  {0.20, 0.35},
                                                        {0.275, 0.20}, {0.275, 0.275}, {0.275, 0.35},
                                                        {0.35, 0.20},  {0.35, 0.275},  {0.35, 0.35}};
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
  o.hold_s = 1e6;  // 28 holds and 2 s of rest: the whole staircase named, not where it stopped
  expectRefusal("staircase1", o, "staircase1: 2.8e+07 s at 80 Hz is 2.24e+09 samples, above the 10000000 one");
  expectRefusal("grid2", o,
                "grid2: longer than the 10000000 samples one experiment holds (34.7 h at 80 Hz): it passes them "
                "within its first 1e+06 s");
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
