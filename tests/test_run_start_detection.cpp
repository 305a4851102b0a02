// How a recording began, at rest or settled (detectRunStart, plsa/diagnose/run_data.hpp), and each start's replay.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "plsa/diagnose/calibration.hpp"
#include "plsa/diagnose/run_data.hpp"
#include "plsa/diagnose/selfcheck.hpp"
#include "plsa/sim/sim_config.hpp"
#include "support/sim_probes.hpp"

using namespace plsa;
using namespace plsa::diagnose;

namespace {

// A settled recording whose first command puts `first_bar` in chamber 1.
RunData startingAt(const sim::SimConfig& truth, double first_bar, std::uint64_t seed) {
  RunData r;
  r.name = "run" + std::to_string(seed);
  r.sample_time_s = 1.0 / truth.sample_rate_hz;
  r.commands = excitationCommands(10, truth.sample_rate_hz, seed);
  r.commands.topRows(80).setZero();
  r.commands.topRows(80).col(0).setConstant(first_bar);
  const SimTrace t = replayCommands(truth, r.commands, seed, settlingTime(truth));
  r.outputs = t.outputs;
  r.pressures = t.pressures;
  r.start = RunStart::kSettled;
  return r;
}

}  // namespace

TEST(RunStartDetection, TellsARecordingFromRestFromASettledOne) {
  sim::SimConfig truth = sim::probes::everyEffectOff();
  RunData settled = startingAt(truth, 0.25, 5);
  settled.start = RunStart::kAuto;
  EXPECT_EQ(detectRunStart(settled, OutputMap::kAngles), RunStart::kSettled);
  RunData rest = settled;
  const SimTrace t = replayCommands(truth, rest.commands, 5, 0.0);  // no pre-roll: from rest
  rest.outputs = t.outputs;
  rest.pressures = t.pressures;
  EXPECT_EQ(detectRunStart(rest, OutputMap::kAngles), RunStart::kAtRest);
  // Without pressures the bending tells; with affine outputs nothing does: at rest, as users record.
  RunData no_p = settled;
  no_p.pressures.resize(0, 0);
  EXPECT_EQ(detectRunStart(no_p, OutputMap::kAngles), RunStart::kSettled);
  EXPECT_EQ(detectRunStart(no_p, OutputMap::kAffine), RunStart::kAtRest);
  no_p.outputs = rest.outputs;
  EXPECT_EQ(detectRunStart(no_p, OutputMap::kAngles), RunStart::kAtRest);
  // A chamber a third of the way up after the first sample period is filling, not settled.
  RunData filling = rest;
  filling.pressures(0, 0) = 0.34 * filling.commands(0, 0);
  EXPECT_EQ(detectRunStart(filling, OutputMap::kAngles), RunStart::kAtRest);
  // A zero first command is a start at rest whatever follows.
  RunData zero = settled;
  zero.commands.row(0).setZero();
  EXPECT_EQ(detectRunStart(zero, OutputMap::kAngles), RunStart::kAtRest);
}

TEST(RunStartDetection, TheSimulatorReplaysEachStartItsOwnWay) {
  sim::SimConfig truth = sim::probes::everyEffectOff();
  truth.sensor.noise_deg = 0.0;
  RunData run = startingAt(truth, 0.25, 6);
  run.start = RunStart::kSettled;
  const double settled_gap = measureGap(truth, {run}, GapOptions{}).total;
  run.start = RunStart::kAtRest;  // replayed from rest: the first second differs
  const double rest_gap = measureGap(truth, {run}, GapOptions{}).total;
  EXPECT_LT(settled_gap, 1e-6);
  EXPECT_GT(rest_gap, 100 * settled_gap + 1e-4);
}
