// The independently written actuator (the diagnosis self-check's "real"
// data): its start, its laws, its refusals.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "plsa/core/angle_units.hpp"
#include "plsa/sim/independent_actuator.hpp"
#include "plsa/sim/sim_config.hpp"

using namespace plsa::sim;

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
    const std::map<std::string, double> strength = {{"deadzone", 0.06},  {"hysteresis", 0.15},   {"stiffening", 1.0},
                                                    {"coupling", 0.8},   {"pneumatic_lag", 0.3}, {"creep", 0.1},
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

// A long line's gas column rings: the chamber's pressure overshoots a step
// and swings back, never below zero; two first-order volumes never overshoot.
TEST(IndependentActuator, AResonantLineRingsWhereTwoVolumesCreep) {
  auto step = [](const std::string& law, double strength) {
    IndependentPhysics p = quietIndependent();
    p.time_constant_s = 0.01;
    setIndependentEffect(p, "pneumatic_lag", law, strength);
    IndependentActuator a(p, 3);
    auto up = holdIndependent(a, {0.3, 0, 0}, 2.0);
    const auto down = holdIndependent(a, {0.0, 0, 0}, 2.0);
    up.insert(up.end(), down.begin(), down.end());
    return up;
  };
  for (double period : {0.1, 0.25}) {
    const auto r = step("resonant_line", period);
    double peak = 0.0, least = 1.0;
    for (const auto& s : r) peak = std::max(peak, s.pressure_bar[0]), least = std::min(least, s.pressure_bar[0]);
    EXPECT_GT(peak, 0.3 * 1.15) << "period " << period;  // damping 0.35 overshoots about 30%
    EXPECT_GE(least, 0.0);
    EXPECT_NEAR(r[159].pressure_bar[0], 0.3, 0.003) << "settled after 2 s";
  }
  double peak = 0.0;
  for (const auto& s : step("two_volume", 0.1)) peak = std::max(peak, s.pressure_bar[0]);
  EXPECT_LT(peak, 0.3 * 1.01);
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

// A mounting offset belongs to the sensor: with its direction set, runs
// recorded with other seeds read the same offset; left unset, each run
// draws its own (a sensor re-mounted per run).
TEST(IndependentActuator, ASensorOffsetsDirectionIsSharedByEveryRunWhenSet) {
  IndependentPhysics p = quietIndependent();
  setIndependentEffect(p, "sensor_bias", "scale_offset", 2.0);
  auto restingOffset = [&](std::uint64_t seed) {
    IndependentActuator a(p, seed);
    return holdIndependent(a, {0, 0, 0}, 1.0).back().bending_deg;
  };
  p.sensor_offset_direction_deg = 120.0;
  const Eigen::Vector2d one = restingOffset(1), other = restingOffset(2);
  EXPECT_NEAR((one - other).norm(), 0.0, 1e-9);
  EXPECT_NEAR(one.norm(), 2.0, 0.05);
  EXPECT_NEAR(std::atan2(one.y(), one.x()) * 180.0 / plsa::kPi, 120.0, 1.0);
  p.sensor_offset_direction_deg = std::numeric_limits<double>::quiet_NaN();
  EXPECT_GT((restingOffset(1) - restingOffset(2)).norm(), 0.1);
  p.sensor_offset_direction_deg = 400.0;
  EXPECT_THROW(IndependentActuator(p, 1), std::invalid_argument);
}

// The generalisation benchmark's bending ranges: the segment's lever rescaled
// until a trajectory's largest bend is the target, also when a stiffening law
// makes the bend grow less than in proportion; the recorded bend agrees.
TEST(IndependentActuator, ScalesItsLeverToABendingRange) {
  Eigen::MatrixXd commands = Eigen::MatrixXd::Zero(8 * 80, 3);
  commands.block(80, 0, 3 * 80, 1).setConstant(0.35);
  commands.block(4 * 80, 1, 3 * 80, 1).setConstant(0.25);
  for (const std::string& stiffening : {std::string(), std::string("duffing")}) {
    IndependentPhysics p = quietIndependent();
    if (!stiffening.empty())
      setIndependentEffect(p, "stiffening", stiffening, independentStrengthRange("stiffening", stiffening).second);
    const double drawn = largestBendDeg(p, commands);
    ASSERT_GT(drawn, 5.0) << stiffening;
    for (const double target : {2.0, 100.0}) {
      IndependentPhysics scaled = p;
      const double reached = scaleToBendRange(scaled, commands, target);
      EXPECT_NEAR(reached, target, 0.02 * target) << stiffening;
      EXPECT_NE(scaled.chamber_radius_m, p.chamber_radius_m);
      IndependentActuator a(scaled, 3);
      double largest = 0.0;
      for (Eigen::Index k = 0; k < commands.rows(); ++k)
        largest = std::max(largest, a.step({commands(k, 0), commands(k, 1), commands(k, 2)}).bending_deg.norm());
      EXPECT_NEAR(largest, reached, 1e-9) << stiffening;
    }
  }
  IndependentPhysics p = quietIndependent();
  EXPECT_THROW(scaleToBendRange(p, commands, 0.0), std::invalid_argument);
  EXPECT_THROW(scaleToBendRange(p, Eigen::MatrixXd::Zero(80, 3), 10.0), std::invalid_argument);
}

TEST(IndependentActuator, TheNoiseFreeReadingIsTheMeasuredOneLessTheWhiteNoise) {
  // The same physics and seed with and without the sensor's white noise:
  // the noisy run's noise-free reading is the quiet run's reading (the
  // sensor's own bias in both), and what the noise adds has its spread.
  IndependentPhysics noisy;
  setIndependentEffect(noisy, "sensor_bias", "warm_up", 1.0);
  noisy.pressure_noise_bar = 0.0;
  IndependentPhysics quiet = noisy;
  quiet.noise_deg = 0.0;
  IndependentActuator a(noisy, 3), b(quiet, 3);
  double sum_sq = 0.0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    const std::array<double, 3> cmd = {k % 400 < 200 ? 0.3 : 0.1, 0.1, 0.0};
    const IndependentSample s = a.step(cmd), q = b.step(cmd);
    ASSERT_LT((s.bending_noise_free_deg - q.bending_deg).norm(), 1e-12) << k;
    EXPECT_EQ(q.bending_noise_free_deg, q.bending_deg);
    sum_sq += (s.bending_deg - s.bending_noise_free_deg).squaredNorm();
  }
  EXPECT_NEAR(std::sqrt(sum_sq / (2 * n)), noisy.noise_deg, 0.1 * noisy.noise_deg);
}
