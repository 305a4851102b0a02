// Banks of plays (IdentifyOptions::play_bank_candidates): several widths
// per input, a Prandtl-Ishlinskii operator weighted by the least squares.
// Their data come from the independently written actuator, whose Preisach
// hysteresis (a triangle of relays) is no play of plsa's.
#include "plsa/sim/independent_recording.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;

namespace {

/// A short search: input side, three single sets, nothing after the bank.
IdentifyOptions bankSearch() {
  IdentifyOptions o;
  o.scheduling = SchedulingChoice::kInputSide;
  o.play_candidates = {{0.0}, {0.04}, {0.1}};
  o.play_coupling_candidates = {};
  o.schedule_lag_candidates = {};
  o.play_threshold_candidates = {};
  o.slow_pole_candidates = {};
  o.output_drift = OutputDriftChoice::kOff;
  return o;
}

/// The bank stage's verdict line (empty when there is none).
std::string bankLine(const IdentifyReport& r) {
  const auto it = std::find_if(r.lines.begin(), r.lines.end(),
                               [](const std::string& l) { return l.rfind("[5/5] banks of plays", 0) == 0; });
  return it == r.lines.end() ? std::string() : *it;
}

struct Runs {
  io::Log train, val;
};

Runs independentRuns(const std::string& hysteresis_law) {
  sim::IndependentPhysics physics;
  if (!hysteresis_law.empty()) {
    const auto [lo, hi] = sim::independentStrengthRange("hysteresis", hysteresis_law);
    sim::setIndependentEffect(physics, "hysteresis", hysteresis_law, 0.5 * (lo + hi));
  }
  sim::ExperimentOptions eo;
  eo.seed = 2;
  return {sim::recordIndependentFromRest(physics, sim::gridExperiment(eo), 1),
          sim::recordIndependentFromRest(physics, sim::joystickExperiment(eo), 101)};
}

}  // namespace

// Preisach hysteresis: the bank scores above every single set held out,
// is kept, and simulates the joystick run it never saw better than the
// single set chosen without it. On a plant without hysteresis no bank is
// kept: it must gain over two standard errors held out.
TEST(Pipeline, ABankOfPlaysIsKeptForPreisachHysteresisAndSimulatesItBetter) {
  const Runs preisach = independentRuns("preisach");
  IdentifyOptions o = bankSearch();
  IdentifyReport with_bank;
  const DioPwlObfModel banked = identifyModel({preisach.train}, o, &with_bank);
  ASSERT_EQ(with_bank.play_bank_scores.size(), 1u);  // uncoupled only: no coupling was chosen
  double best_single = -INFINITY;
  for (const auto& [set, score] : with_bank.play_scores) best_single = std::max(best_single, score);
  EXPECT_GT(with_bank.play_bank_scores[0].score, best_single + 0.5);
  // Kept by the two-standard-error rule (a bank triples the later stages' regressors).
  EXPECT_GT(with_bank.play_bank_gain.first, 2.0 * with_bank.play_bank_gain.second);
  ASSERT_EQ(banked.shaping.play.size(), 3u);
  for (const auto& channels : banked.shaping.play) EXPECT_EQ(channels.size(), 3u);

  // The least gain kept: the same bank, asked to gain a little more than it
  // does, is left out and the line says why.
  IdentifyOptions demanding = o;
  demanding.play_bank_min_gain = with_bank.play_bank_gain.first + 0.01;
  IdentifyReport under_least_gain;
  const DioPwlObfModel unbanked = identifyModel({preisach.train}, demanding, &under_least_gain);
  for (const auto& channels : unbanked.shaping.play) EXPECT_EQ(channels.size(), 1u);
  EXPECT_EQ(under_least_gain.play_bank_gain, with_bank.play_bank_gain);
  EXPECT_NE(bankLine(under_least_gain).find("under the least gain kept"), std::string::npos)
      << bankLine(under_least_gain);

  o.play_bank_candidates = {};
  IdentifyReport without_bank;
  const DioPwlObfModel single = identifyModel({preisach.train}, o, &without_bank);
  EXPECT_TRUE(without_bank.play_bank_scores.empty());
  for (const auto& channels : single.shaping.play) EXPECT_EQ(channels.size(), 1u);
  const eval::ValidationResult b = eval::validateModel(banked, preisach.val, {40});
  const eval::ValidationResult s = eval::validateModel(single, preisach.val, {40});
  for (std::size_t out = 0; out < 2; ++out) {
    std::printf("%s: bank %.2f / %.2f, single set %.2f / %.2f (40 steps / simulation)\n", b.outputs[out].name.c_str(),
                b.outputs[out].fit_k.at(40), b.outputs[out].fit_sim, s.outputs[out].fit_k.at(40),
                s.outputs[out].fit_sim);
    EXPECT_GT(b.outputs[out].fit_k.at(40), s.outputs[out].fit_k.at(40)) << b.outputs[out].name;
  }
  EXPECT_GT(b.outputs[0].fit_sim, s.outputs[0].fit_sim + 5.0);

  const Runs plain = independentRuns("");
  IdentifyReport no_hysteresis;
  const DioPwlObfModel linear = identifyModel({plain.train}, bankSearch(), &no_hysteresis);
  ASSERT_EQ(no_hysteresis.play_bank_scores.size(), 1u);
  EXPECT_LE(no_hysteresis.play_bank_gain.first, 2.0 * no_hysteresis.play_bank_gain.second);
  for (const auto& channels : linear.shaping.play) EXPECT_EQ(channels.size(), 1u);
  EXPECT_NE(bankLine(no_hysteresis).find("none kept"), std::string::npos) << bankLine(no_hysteresis);
}

// A bank is two or more plays; one is a set for --play. The least gain
// kept is a finite number of fit points, not negative.
TEST(Pipeline, ABankOfOnePlayIsRefusedByName) {
  const Runs plain = independentRuns("");
  IdentifyOptions o = bankSearch();
  o.play_bank_candidates = {{PlayChannel(0.1)}};
  plsa::test_fixtures::expectThrowContaining([&] { identifyModel({plain.train}, o); },
                                             "a bank of plays needs at least two channels");
  for (const double bad : {-0.5, static_cast<double>(NAN), static_cast<double>(INFINITY)}) {
    IdentifyOptions b = bankSearch();
    b.play_bank_min_gain = bad;
    plsa::test_fixtures::expectThrowContaining([&] { identifyModel({plain.train}, b); },
                                               "the least gain that keeps a bank of plays");
  }
}
