// Identification where some signals are weak: outputs too weak for their
// step fits or for any fit (the partition still follows the design, the
// poles come from windows or from the other outputs), and an input that
// only reads noise (left out of a quantile grid); and pressures logged in
// another unit than bar.
#include "plsa/identify/baselines.hpp"
#include "support/identify_fixtures.hpp"

using namespace plsa;
using namespace plsa::identify;

namespace {

constexpr double kDt = 1.0 / 80.0;

// A staircase on p_1 and two outputs with noise 0.02: "strong", and "weak",
// slow and weak (a 0.05 bar step moves it 0.25 over 4 s) or, kWeakIsNoise,
// noise alone; kBothWeak: "strong" is like "weak".
enum class Weakness { kOneWeak, kBothWeak, kWeakIsNoise };
io::Log staircaseLog(Weakness weakness) {
  const std::vector<double> levels = {0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.3, 0.25, 0.2, 0.15, 0.1, 0.05, 0.0};
  const auto hold = static_cast<Eigen::Index>(4.0 / kDt);
  const Eigen::Index n = hold * static_cast<Eigen::Index>(levels.size() + 1);
  io::Log log;
  log.source = "weak_output.csv";
  log.columns = {"time_s", "cmd_1", "p_1", "strong", "weak"};
  log.data.resize(n, 5);
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.02);
  double p = 0.0, strong = 0.0, weak = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index step = k / hold;
    const double cmd = step == 0 ? 0.0 : levels[static_cast<std::size_t>(step - 1)];
    p = 0.9 * p + 0.1 * cmd;
    strong = weakness == Weakness::kBothWeak ? 0.99 * strong + 0.01 * 5.0 * p : 0.95 * strong + 0.05 * 100.0 * p;
    weak = weakness == Weakness::kWeakIsNoise ? 0.0 : 0.99 * weak + 0.01 * 5.0 * p;
    log.data.row(k) << static_cast<double>(k) * kDt, cmd, p + 0.001 * noise(rng), strong + noise(rng),
        weak + noise(rng);
  }
  return log;
}

// A log of n samples with these columns, its data to be filled.
io::Log blankLog(std::string source, std::vector<std::string> columns, Eigen::Index n) {
  io::Log log;
  log.source = std::move(source);
  log.columns = std::move(columns);
  log.data.resize(n, static_cast<Eigen::Index>(log.columns.size()));
  return log;
}

// A reference that holds one step and then keeps moving (a joystick run that
// happens to pause once), through two first-order lags (poles 0.9 and 0.95);
// `creep`: fast lags (0.5, 0.5) and a slow creep (0.999) as large as they.
io::Log oneStepLog(bool creep = false) {
  const Eigen::Index rest = 160, held = 320, n = 8000;
  io::Log log = blankLog("one_step.csv", {"time_s", "cmd_1", "p_1", "y"}, n);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double lag_p = creep ? 0.5 : 0.9, lag_y = creep ? 0.5 : 0.95, creep_gain = creep ? 40.0 : 0.0;
  double cmd = 0.0, p = 0.0, y = 0.0, c = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k == rest) cmd = 0.2;
    if (k >= rest + held) cmd = std::clamp(cmd + 0.01 * noise(rng), 0.05, 0.35);
    p = lag_p * p + (1.0 - lag_p) * cmd;
    y = lag_y * y + (1.0 - lag_y) * 40.0 * p;
    c = 0.999 * c + 0.001 * creep_gain * p;
    log.data.row(k) << static_cast<double>(k) * kDt, cmd, p, y + c + 0.05 * noise(rng);
  }
  return log;
}

// Two chambers: four steps on cmd_2 (z follows p_2, pole 0.95), then one on
// cmd_1 held 4 s and random moves after it (y follows p_1, pole 0.9): y's
// steps give one usable pole, z's four.
io::Log twoChamberLog() {
  const Eigen::Index hold = 320, n = 8000;
  io::Log log = blankLog("two_chambers.csv", {"time_s", "cmd_1", "cmd_2", "p_1", "p_2", "y", "z"}, n);
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 1.0);
  double cmd_1 = 0.0, cmd_2 = 0.0, p_1 = 0.0, p_2 = 0.0, y = 0.0, z = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index step = k / hold;
    if (step >= 1 && step <= 4) cmd_2 = 0.08 * static_cast<double>(step);
    if (step == 5) cmd_1 = 0.2;
    if (step >= 6) cmd_1 = std::clamp(cmd_1 + 0.01 * noise(rng), 0.05, 0.35);
    p_1 = 0.5 * p_1 + 0.5 * cmd_1;
    p_2 = 0.5 * p_2 + 0.5 * cmd_2;
    y = 0.9 * y + 0.1 * 40.0 * p_1;
    z = 0.95 * z + 0.05 * 40.0 * p_2;
    log.data.row(k) << static_cast<double>(k) * kDt, cmd_1, cmd_2, p_1, p_2, y + 0.05 * noise(rng),
        z + 0.05 * noise(rng);
  }
  return log;
}

// The identify progress line that starts with `tag`.
std::string progressLine(const IdentifyReport& rep, const std::string& tag) {
  const auto line = std::find_if(rep.lines.begin(), rep.lines.end(),
                                 [&](const std::string& l) { return l.find(tag) != std::string::npos; });
  return line == rep.lines.end() ? std::string() : *line;
}

// Only the partition's choice: one play set, no lag, threshold, slow pole or drift.
IdentifyOptions partitionOnly(std::vector<std::string> inputs, std::vector<std::string> outputs) {
  IdentifyOptions o;
  o.inputs = std::move(inputs);
  o.outputs = std::move(outputs);
  o.scheduling = SchedulingChoice::kSwitched;
  o.play_candidates = {{0.0}};
  o.play_coupling_candidates.clear();
  o.schedule_lag_candidates.clear();
  o.play_threshold_candidates.clear();
  o.slow_pole_candidates.clear();
  o.output_drift = OutputDriftChoice::kOff;
  return o;
}

// Switched regions split midway between the staircase's levels above the vented one.
void expectStaircaseSplits(const DioPwlObfModel& m, const IdentifyReport& rep) {
  ASSERT_EQ(m.partition.breakpoints().size(), 1u);
  const auto& b = m.partition.breakpoints()[0];
  ASSERT_EQ(b.size(), 6u);
  for (std::size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i], 0.075 + 0.05 * static_cast<double>(i), 1e-9);
  for (const auto& l : rep.lines) EXPECT_EQ(l.find("quantile grid"), std::string::npos) << l;
}

}  // namespace

// A staircase whose second output is too weak for a single step's fit (SNR
// about 5 against the 8 required) but clear over a window of two steps: that
// output's poles come from windows, and the partition still follows the
// staircase's levels, not quantiles of the measured pressure.
TEST(Pipeline, OneWeakOutputKeepsTheStaircasePartition) {
  IdentifyReport rep;
  const DioPwlObfModel m =
      identifyModel({staircaseLog(Weakness::kOneWeak)}, partitionOnly({"p_1"}, {"strong", "weak"}), &rep);
  EXPECT_TRUE(rep.staircase);
  EXPECT_TRUE(rep.used_windows);
  EXPECT_EQ(rep.window_outputs, (std::vector<std::string>{"weak"}));
  const auto line = std::find_if(rep.lines.begin(), rep.lines.end(),
                                 [](const std::string& l) { return l.find("[2/5]") != std::string::npos; });
  ASSERT_NE(line, rep.lines.end());
  EXPECT_NE(line->find("no usable step responses for weak:"), std::string::npos) << *line;
  expectStaircaseSplits(m, rep);
}

// The same staircase logged in MPa or kPa instead of bar: a step is a change
// above 0.005 or 2.5% of the reference's top level, whichever is smaller, so
// it is cut into the same steps, gives the same poles and splits at the same
// levels in its unit (an absolute 0.005 missed MPa's 0.005 steps: 6 segments
// of the 14 here).
TEST(Pipeline, PressuresInAnyUnitAreCutIntoTheSameSteps) {
  const io::Log in_bar = staircaseLog(Weakness::kOneWeak);
  const IdentifyOptions o = partitionOnly({"p_1"}, {"strong", "weak"});
  IdentifyReport bar;
  const DioPwlObfModel m_bar = identifyModel({in_bar}, o, &bar);
  ASSERT_GT(bar.segments, 10);
  for (const double unit : {0.1, 100.0}) {
    io::Log log = in_bar;
    log.data.col(1) *= unit;  // cmd_1
    log.data.col(2) *= unit;  // p_1
    IdentifyReport rep;
    const DioPwlObfModel m = identifyModel({log}, o, &rep);
    EXPECT_EQ(rep.segments, bar.segments) << unit;
    EXPECT_TRUE(rep.staircase) << unit;
    ASSERT_EQ(m.partition.breakpoints().size(), 1u);
    const auto &b = m.partition.breakpoints()[0], &b_bar = m_bar.partition.breakpoints()[0];
    ASSERT_EQ(b.size(), b_bar.size()) << unit;
    for (std::size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i], unit * b_bar[i], 1e-9 * unit) << unit;
    ASSERT_EQ(rep.pairs.size(), bar.pairs.size());
    for (std::size_t i = 0; i < rep.pairs.size(); ++i) {
      // The same set (its order may differ). The strong output's poles come
      // from the steps alike in every unit; the noise-level output's from
      // second-order window fits, which round differently: by about 1e-4 on
      // one host, 1.5e-3 on another (cut into other steps, 0.014 apart).
      auto poles = rep.pairs[i].chosen.centres, poles_bar = bar.pairs[i].chosen.centres;
      ASSERT_EQ(poles.size(), poles_bar.size()) << unit;
      ASSERT_EQ(rep.pairs[i].output, bar.pairs[i].output);
      const bool weak = rep.pairs[i].output == 1;
      const auto by_real = [](std::complex<double> a, std::complex<double> b) { return a.real() < b.real(); };
      std::sort(poles.begin(), poles.end(), by_real);
      std::sort(poles_bar.begin(), poles_bar.end(), by_real);
      for (std::size_t k = 0; k < poles.size(); ++k)
        EXPECT_NEAR(std::abs(poles[k] - poles_bar[k]), 0.0, weak ? 5e-3 : 1e-9) << unit << (weak ? " weak" : " strong");
    }
  }
}

// Both outputs too weak for any step's fit (a nearly straight segment, as the
// generalisation benchmark's 2 deg rows record): the poles come from windows,
// and the design is still the reference's staircase.
TEST(Pipeline, EveryOutputWeakKeepsTheStaircasePartition) {
  IdentifyReport rep;
  const DioPwlObfModel m =
      identifyModel({staircaseLog(Weakness::kBothWeak)}, partitionOnly({"p_1"}, {"strong", "weak"}), &rep);
  EXPECT_FALSE(rep.staircase) << "no output's poles came from its steps";
  EXPECT_EQ(rep.window_outputs, (std::vector<std::string>{"strong", "weak"}));
  expectStaircaseSplits(m, rep);
}

// The staircase logged without its command and with a noisy pressure
// sensor (3 mbar): the pressure is its own reference, its noise cuts it at
// nearly every sample, and its plateaus give back the commanded steps and
// the same splits. (Pipeline.StaircaseWithoutCommandsStepsOnThePressuresPlateaus
// compares the fits held out on the simulator, in the Release stage.)
TEST(Pipeline, AStaircaseWithoutItsCommandStepsOnThePressuresPlateaus) {
  const io::Log commanded = staircaseLog(Weakness::kOneWeak);
  io::Log pressure_only = blankLog("no_command.csv", {"time_s", "p_1", "strong", "weak"}, commanded.samples());
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.003);
  pressure_only.data << commanded.data.col(0), commanded.data.col(2), commanded.data.col(3), commanded.data.col(4);
  for (Eigen::Index k = 0; k < pressure_only.samples(); ++k) pressure_only.data(k, 1) += noise(rng);
  const IdentifyOptions o = partitionOnly({"p_1"}, {"strong", "weak"});
  IdentifyReport with, without;
  identifyModel({commanded}, o, &with);
  const DioPwlObfModel m = identifyModel({pressure_only}, o, &without);
  EXPECT_FALSE(with.references_from_plateaus);
  ASSERT_TRUE(without.references_from_plateaus) << progressLine(without, "[2/5]");
  EXPECT_EQ(without.segments, with.segments);
  ASSERT_EQ(m.partition.breakpoints().size(), 1u);
  const auto& b = m.partition.breakpoints()[0];
  ASSERT_EQ(b.size(), 6u);
  for (std::size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i], 0.075 + 0.05 * static_cast<double>(i), 0.002);
  EXPECT_NE(progressLine(without, "[2/5] step references:").find(std::to_string(with.segments) + " step segments"),
            std::string::npos);
}

// One step's single local pole is too few to place a bank's five: local
// windows are fitted too, but while the steps' model (five times the one
// pole, a Laguerre basis) scores above window_poles_below, their poles are
// not tried.
TEST(Pipeline, OneStepAmongMovingInputsKeepsItsRepeatedPoleWhileItScores) {
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({oneStepLog()}, partitionOnly({"p_1"}, {"y"}), &rep);
  EXPECT_EQ(rep.segments, 1);
  EXPECT_TRUE(rep.window_outputs.empty());
  EXPECT_EQ(rep.window_candidate_outputs, (std::vector<std::string>{"y"}));
  EXPECT_EQ(rep.pairs.at(0).identified.size(), 1u);
  EXPECT_GE(rep.pairs.at(0).window_identified.size(), 5u);
  ASSERT_EQ(rep.pole_method_scores.size(), 2u);
  EXPECT_GE(rep.pole_method_scores[0].step_ahead, 0.0);
  EXPECT_NE(progressLine(rep, "[2/5]").find("fewer usable step poles than the 5 to place for y"), std::string::npos);
  EXPECT_NE(progressLine(rep, "[5/5] poles kept").find("windows' poles for y not tried"), std::string::npos);
  const auto poles = m.poles[0][0].poles();
  ASSERT_EQ(poles.size(), 5u);
  for (const auto& q : poles) EXPECT_EQ(q, poles[0]) << "the step's one pole, five times";
}

// window_poles_below 100: the steps' and windows' poles together are two
// more candidates, and the model keeps the best of the four by held-out
// score (the first unless another beats it by 0.1), with its poles. With a
// creep, the step's one pole follows it and the windows' poles score higher.
TEST(Pipeline, WindowPolesCompeteWithTheStepsWhenAskedTo) {
  IdentifyOptions o = partitionOnly({"p_1"}, {"y"});
  o.window_poles_below = 100.0;
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({oneStepLog(true)}, o, &rep);
  ASSERT_EQ(rep.pole_method_scores.size(), 4u);
  EXPECT_EQ(rep.pole_method_scores[2].method, "fkcm+windows");
  EXPECT_EQ(rep.pole_method_scores[3].method, "fcm+windows");
  std::size_t best = 0;
  for (std::size_t i = 1; i < 4; ++i)
    if (rep.pole_method_scores[i].step_ahead > rep.pole_method_scores[best].step_ahead + 0.1) best = i;
  EXPECT_NE(progressLine(rep, "[5/5] poles kept").find("poles kept: " + rep.pole_method_scores[best].method + " "),
            std::string::npos)
      << progressLine(rep, "[5/5] poles kept");
  const auto poles = m.poles[0][0].poles();
  const bool repeated =
      std::all_of(poles.begin(), poles.end(), [&](const auto& q) { return std::abs(q - poles[0]) < 1e-9; });
  EXPECT_GE(best, 2u) << progressLine(rep, "[5/5] poles kept");
  EXPECT_EQ(repeated, best < 2) << "the steps' candidates repeat their one pole; the windows' do not";
}

// The windows' candidates cluster only the short output's poles anew: z,
// whose steps give poles enough, reuses the steps' candidates' clustering
// and is not printed again.
TEST(Pipeline, WindowCandidatesClusterOnlyTheShortOutputsPolesAgain) {
  IdentifyOptions o = partitionOnly({"p_1", "p_2"}, {"y", "z"});
  o.poles_per_pair = 3;
  o.window_poles_below = 100.0;
  IdentifyReport rep;
  identifyModel({twoChamberLog()}, o, &rep);
  ASSERT_EQ(rep.window_candidate_outputs, (std::vector<std::string>{"y"}));
  ASSERT_EQ(rep.pole_method_scores.size(), 4u);
  int y_lines = 0, z_lines = 0, with_windows = 0;
  for (const auto& l : rep.lines) {
    if (l.rfind("[3/5] poles", 0) != 0) continue;
    y_lines += l.find("-> y ") != std::string::npos;
    z_lines += l.find("-> z ") != std::string::npos;
    if (l.find("(with windows)") == std::string::npos) continue;
    ++with_windows;
    EXPECT_NE(l.find("-> y "), std::string::npos) << l;
  }
  EXPECT_EQ(z_lines, 4) << "z: each input once per method";
  EXPECT_EQ(y_lines, 8) << "y: each input once per method, then again with its windows";
  EXPECT_EQ(with_windows, 4);
}

// Without a design, the grid is quantiles of the inputs that move: a chamber
// that is never driven, whose sensor reads only noise, is not scheduled on.
TEST(Pipeline, QuantileGridLeavesOutAnInputThatOnlyReadsNoise) {
  const Eigen::Index n = 6000;
  io::Log log = blankLog("unused_chamber.csv", {"time_s", "p_1", "p_2", "y"}, n);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  double p = 0.2, y = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    p = std::clamp(p + 0.01 * noise(rng), 0.05, 0.35);
    y = 0.95 * y + 0.05 * 40.0 * p;
    log.data.row(k) << static_cast<double>(k) * kDt, p, 0.003 * noise(rng), y + 0.05 * noise(rng);
  }
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({log}, partitionOnly({"p_1", "p_2"}, {"y"}), &rep);
  EXPECT_EQ(m.partition.inputs(), (std::vector<int>{0})) << "p_2's noise spans more than a step's threshold";
  const auto line = std::find_if(rep.lines.begin(), rep.lines.end(),
                                 [](const std::string& l) { return l.find("quantile grid") != std::string::npos; });
  ASSERT_NE(line, rep.lines.end());
  EXPECT_EQ(line->find("p_2"), std::string::npos) << *line;
}

// Inputs that never leave a step's band (a dither of under 5 mbar): no
// input to schedule on, one region, and so no quantile grid to report.
TEST(Pipeline, NoMovingInputReportsNoQuantileGrid) {
  const Eigen::Index n = 6000;
  io::Log log = blankLog("dither.csv", {"time_s", "p_1", "y"}, n);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> dither(-0.002, 0.002);
  double y = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const double p = 0.2 + dither(rng);
    y = 0.95 * y + 0.05 * 40.0 * p;
    log.data.row(k) << static_cast<double>(k) * kDt, p, y;
  }
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({log}, partitionOnly({"p_1"}, {"y"}), &rep);
  EXPECT_EQ(m.partition.regionCount(), 1);
  EXPECT_EQ(rep.grid_levels, 0) << "a grid reported where no input moves";
  EXPECT_TRUE(rep.grid_level_scores.empty());
}

// Three chambers moved at random, no staircase: `seconds` of a quantile
// grid's data, its output a lag of their sum.
io::Log randomChambersLog(double seconds) {
  const auto n = static_cast<Eigen::Index>(seconds / kDt);
  io::Log log = blankLog("random_chambers.csv", {"time_s", "p_1", "p_2", "p_3", "y"}, n);
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 1.0);
  double p[3] = {0.2, 0.2, 0.2}, y = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    for (double& pj : p) pj = std::clamp(pj + 0.01 * noise(rng), 0.05, 0.35);
    y = 0.95 * y + 0.05 * 40.0 * (p[0] + 0.8 * p[1] + 0.6 * p[2]);
    log.data.row(k) << static_cast<double>(k) * kDt, p[0], p[1], p[2], y + 0.05 * noise(rng);
  }
  return log;
}

// Columns that hold one value in every sample (a wrong --inputs or --outputs
// name, typically) are refused before any work, naming them; an output
// that moves through inputs that hold is not a model either.
TEST(Pipeline, StillColumnsAreRefusedNamingThem) {
  const auto whyRefused = [](const io::Log& log, const std::vector<std::string>& inputs) {
    try {
      identifyModel({log}, partitionOnly(inputs, {"y"}));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  io::Log still_output = randomChambersLog(120.0);
  still_output.data.col(4).setConstant(2.5);
  EXPECT_EQ(whyRefused(still_output, {"p_1", "p_2", "p_3"}),
            "identify: output 'y' holds 2.5 in every sample of the logs: there is no response to identify (check "
            "--outputs)");
  io::Log still_inputs = randomChambersLog(120.0);
  still_inputs.data.col(1).setZero();
  still_inputs.data.col(2).setConstant(0.2);
  EXPECT_EQ(whyRefused(still_inputs, {"p_1", "p_2"}),
            "identify: the inputs (p_1, p_2) hold one value each in every sample of the logs: nothing drives a "
            "response (check --inputs)");
  EXPECT_EQ(whyRefused(still_inputs, {"p_1", "p_2", "p_3"}).find("hold one value"), std::string::npos)
      << "one input moving is enough";
}

// Found by a probe: outputs times 1e300 failed as "fitCoefficients: the
// regressors are all zero", outputs near 1e-299 as "the measured signal is
// constant"; each is named by its magnitude now, before any work.
TEST(Pipeline, ColumnsBeyondWhatAFitTakesAreRefusedNamingThem) {
  const auto whyRefused = [](const io::Log& log) {
    try {
      identifyModel({log}, partitionOnly({"p_1", "p_2", "p_3"}, {"y"}));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  io::Log huge = randomChambersLog(120.0), tiny = huge, huge_input = huge;
  huge.data.col(4) *= 1e300;
  tiny.data.col(4) *= 1e-300;
  huge_input.data.col(2) *= 1e200;
  EXPECT_NE(whyRefused(huge).find("identify: column 'y' reaches "), std::string::npos) << whyRefused(huge);
  EXPECT_NE(whyRefused(huge).find("values beyond 1e150 cannot be fitted"), std::string::npos);
  EXPECT_NE(whyRefused(huge_input).find("identify: column 'p_2' reaches "), std::string::npos)
      << whyRefused(huge_input);
  EXPECT_NE(whyRefused(tiny).find("identify: output 'y' moves by only "), std::string::npos) << whyRefused(tiny);
}

// A log given twice (from Python, where no path check runs) or a copy under
// another name: its samples would sit in the training and the held-out folds
// at once. Refused naming both; another log of the same length is taken.
TEST(Pipeline, ALogGivenTwiceIsRefused) {
  io::Log a = randomChambersLog(120.0);
  a.source = "a.csv";
  io::Log copy = a;
  copy.source = "a_copy.csv";
  try {
    identifyModel({a, copy}, partitionOnly({"p_1", "p_2", "p_3"}, {"y"}));
    ADD_FAILURE() << "a copy was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("identify: a_copy.csv holds the same samples as a.csv (a log given twice, or "
                                         "a copy)"),
              std::string::npos)
        << e.what();
  }
  io::Log other = a;
  other.source = "b.csv";
  other.data.col(4).array() += 0.01;  // the same commands, another response
  EXPECT_NO_THROW(identifyModel({a, other}, partitionOnly({"p_1", "p_2", "p_3"}, {"y"})));
}

// A column named twice among the inputs and outputs, or the time as one of
// them, is refused before any work (before, after the whole identification,
// by the model file; the time identified as a signal).
TEST(Pipeline, AColumnNamedTwiceOrTheTimeIsRefusedBeforeAnyWork) {
  const io::Log log = randomChambersLog(120.0);
  const auto whyRefused = [&log](const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
    try {
      identifyModel({log}, partitionOnly(inputs, outputs));
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(whyRefused({"p_1", "p_1"}, {"y"}),
            "identify: column 'p_1' is named twice among the inputs and outputs (check --inputs, --outputs)");
  EXPECT_EQ(whyRefused({"p_1", "p_2"}, {"p_2"}),
            "identify: column 'p_2' is named twice among the inputs and outputs (check --inputs, --outputs)");
  EXPECT_EQ(whyRefused({"time_s"}, {"y"}),
            "identify: 'time_s' is the logs' time, not an input or output (check --inputs, --outputs)");
}

// By default a chamber's pressure steps on its own command: --inputs p_2
// alone takes cmd_2's staircase (0.08 to 0.32 bar in four steps), not
// cmd_1's, which the first input's position would give.
TEST(Pipeline, AnInputStepsOnItsOwnChambersCommand) {
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({twoChamberLog()}, partitionOnly({"p_2"}, {"z"}), &rep);
  ASSERT_EQ(m.partition.breakpoints().size(), 1u);
  const auto& b = m.partition.breakpoints()[0];
  ASSERT_EQ(b.size(), 3u) << progressLine(rep, "[4/5] partition");
  for (std::size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i], 0.12 + 0.08 * static_cast<double>(i), 1e-9);
  IdentifyOptions on_cmd_1 = partitionOnly({"p_2"}, {"z"});
  on_cmd_1.reference = {"cmd_1"};
  const DioPwlObfModel other = identifyModel({twoChamberLog()}, on_cmd_1);
  EXPECT_NE(other.partition.breakpoints(), m.partition.breakpoints()) << "the test tells the references apart";
}

// quantile_levels 0 (the default): 3 levels per moving input, or 2 when 3
// would leave under 10 s of data per region (three chambers: 270 s), then
// finer counts scored while they leave 10 s per region; a number given is kept.
TEST(Pipeline, QuantileGridTakesTwoLevelsWhenThreeWouldLeaveRegionsShortOfData) {
  IdentifyOptions o = partitionOnly({"p_1", "p_2", "p_3"}, {"y"});
  ASSERT_EQ(o.quantile_levels, 0);
  IdentifyReport short_rep, long_rep, asked_rep;
  const DioPwlObfModel short_model = identifyModel({randomChambersLog(120.0)}, o, &short_rep);
  EXPECT_EQ(short_model.partition.regionCount(), 8);
  const std::string line = progressLine(short_rep, "[4/5] partition");
  EXPECT_NE(line.find("quantile grid of 2 levels"), std::string::npos) << line;
  EXPECT_NE(line.find("3 would leave under 10 s of data per region"), std::string::npos) << line;
  EXPECT_TRUE(short_rep.grid_level_scores.empty()) << "120 s leave 3 levels' regions under 10 s: nothing to score";
  EXPECT_EQ(short_rep.grid_levels, 2);
  // 300 s: 3 levels (11 s per region); 4 would leave 4.7 s, so nothing finer is scored.
  const DioPwlObfModel long_model = identifyModel({randomChambersLog(300.0)}, o, &long_rep);
  EXPECT_TRUE(long_rep.grid_level_scores.empty()) << progressLine(long_rep, "[5/5] quantile grid");
  EXPECT_EQ(long_rep.grid_levels, 3);
  EXPECT_EQ(long_model.partition.regionCount(), 27);
  o.quantile_levels = 3;
  EXPECT_EQ(identifyModel({randomChambersLog(120.0)}, o, &asked_rep).partition.regionCount(), 27);
  EXPECT_EQ(progressLine(asked_rep, "[4/5] partition").find("would leave"), std::string::npos);
  EXPECT_TRUE(asked_rep.grid_level_scores.empty());
  o.quantile_levels = -1;
  EXPECT_THROW(identifyModel({randomChambersLog(20.0)}, o), std::invalid_argument);
}

// One chamber moved at random through a gain that grows steeply with its
// level (a cubic static map): the finer grids follow the gain, so the
// scored stage keeps more levels than the automatic 3; through a constant
// gain the automatic count stands. Counts are tried one level finer at a
// time from the automatic one.
io::Log oneChamberLog(bool steep) {
  const double seconds = 200.0;  // 5 levels leave 40 s per region
  const auto n = static_cast<Eigen::Index>(seconds / kDt);
  io::Log l = blankLog("one_chamber.csv", {"time_s", "p_1", "y"}, n);
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 1.0);
  double p = 0.2, y = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    p = std::clamp(p + 0.01 * noise(rng), 0.0, 0.4);
    const double level = steep ? 40.0 * p * p * p / 0.04 : 40.0 * p;
    y = 0.95 * y + 0.05 * level;
    l.data.row(k) << static_cast<double>(k) * kDt, p, y + 0.05 * noise(rng);
  }
  return l;
}

TEST(Pipeline, QuantileGridLevelsAreChosenByHeldOutScore) {
  auto log = oneChamberLog;
  IdentifyOptions o = partitionOnly({"p_1"}, {"y"});
  IdentifyReport steep, flat;
  const DioPwlObfModel m = identifyModel({log(true)}, o, &steep);
  // From the automatic 3, one level finer at a time while it gains.
  ASSERT_GE(steep.grid_level_scores.size(), 2u) << progressLine(steep, "[5/5] quantile grid");
  EXPECT_EQ(steep.grid_level_scores.front().levels, 3) << progressLine(steep, "[5/5] quantile grid");
  EXPECT_EQ(steep.grid_level_scores.front().structure, "S") << "the options give switched scheduling alone";
  EXPECT_GT(steep.grid_levels, 3) << progressLine(steep, "[5/5] quantile grid");
  for (std::size_t i = 1; i < steep.grid_level_scores.size(); ++i)
    EXPECT_EQ(steep.grid_level_scores[i].levels, steep.grid_level_scores[i - 1].levels + 1);
  EXPECT_EQ(m.partition.regionCount(), steep.grid_levels);
  EXPECT_NE(progressLine(steep, "[5/5] quantile grid").find("kept " + std::to_string(steep.grid_levels) + " levels"),
            std::string::npos);
  identifyModel({log(false)}, o, &flat);
  // 4 levels gain nothing: 5 is not scored.
  ASSERT_EQ(flat.grid_level_scores.size(), 2u) << progressLine(flat, "[5/5] quantile grid");
  EXPECT_EQ(flat.grid_level_scores.back().levels, 4);
  EXPECT_EQ(flat.grid_levels, 3) << progressLine(flat, "[5/5] quantile grid");
  // Not scored (the paper's configuration): the automatic count.
  o.score_grid_levels = false;
  IdentifyReport unscored;
  EXPECT_EQ(identifyModel({log(true)}, o, &unscored).partition.regionCount(), 3);
  EXPECT_TRUE(unscored.grid_level_scores.empty());
  EXPECT_EQ(unscored.grid_levels, 3);
}

// The play stage takes the first play set's scores on the kept grid from the
// level stage (input side only there) and scores the rest itself: every
// score, and the model, as when the kept count is given.
TEST(Pipeline, PlayStageReusesTheGridLevelStagesScores) {
  IdentifyOptions o = partitionOnly({"p_1"}, {"y"});
  o.scheduling = SchedulingChoice::kAuto;
  o.play_candidates = {{0.0}, {0.05}};
  IdentifyReport chosen, given;
  const DioPwlObfModel a = identifyModel({oneChamberLog(true)}, o, &chosen);
  ASSERT_GT(chosen.grid_levels, 3) << progressLine(chosen, "[5/5] quantile grid");
  EXPECT_EQ(chosen.grid_level_scores.front().structure, "N");
  o.quantile_levels = chosen.grid_levels;
  const DioPwlObfModel b = identifyModel({oneChamberLog(true)}, o, &given);
  EXPECT_TRUE(given.grid_level_scores.empty());
  ASSERT_EQ(chosen.play_scores.size(), given.play_scores.size());
  ASSERT_EQ(chosen.play_scores.size(), 6u) << "two play sets on I, N and S";
  for (std::size_t i = 0; i < chosen.play_scores.size(); ++i)
    EXPECT_EQ(chosen.play_scores[i].second, given.play_scores[i].second) << i;
  const auto kept = std::find_if(chosen.grid_level_scores.begin(), chosen.grid_level_scores.end(),
                                 [&](const GridLevelScore& g) { return g.levels == chosen.grid_levels; });
  ASSERT_NE(kept, chosen.grid_level_scores.end());
  EXPECT_EQ(chosen.play_scores[2].second, kept->step_ahead) << "N's first set on the kept grid";
  EXPECT_EQ(a.partition.regionCount(), b.partition.regionCount());
  EXPECT_EQ(a.coefficients, b.coefficients);
}

// Random excitation gives no step: the poles come from windows, and the same
// windows fitted at second order give two more candidates ("+order2"),
// scored with the others; asked for second-order local fits, there is no
// second set to offer.
TEST(Pipeline, WindowsInsteadOfStepsAlsoOfferTheirSecondOrderPoles) {
  IdentifyOptions o = partitionOnly({"p_1", "p_2", "p_3"}, {"y"});
  IdentifyReport rep;
  identifyModel({randomChambersLog(120.0)}, o, &rep);
  ASSERT_EQ(rep.window_outputs, (std::vector<std::string>{"y"}));
  EXPECT_TRUE(std::any_of(rep.pairs.begin(), rep.pairs.end(),
                          [](const PairPoles& pp) { return !pp.window_second_order.empty(); }));
  std::vector<std::string> names;
  for (const auto& s : rep.pole_method_scores) names.push_back(s.method);
  EXPECT_EQ(names, (std::vector<std::string>{"fkcm", "fcm", "fkcm+order2", "fcm+order2"}));
  EXPECT_NE(progressLine(rep, "[3/5] poles (order 2)").find("own (order 2) poles"), std::string::npos)
      << progressLine(rep, "[3/5] poles (order 2)");
  EXPECT_NE(progressLine(rep, "[5/5] poles kept").find("fkcm+order2->"), std::string::npos);
  // Offered only while the first-order poles score below the bound; the
  // paper's configuration never fits them.
  IdentifyOptions bounded = o;
  bounded.second_order_windows_below = -1e9;
  IdentifyReport held;
  identifyModel({randomChambersLog(120.0)}, bounded, &held);
  EXPECT_EQ(held.pole_method_scores.size(), 2u);
  EXPECT_NE(progressLine(held, "[5/5] poles kept").find("second-order windows' poles not tried"), std::string::npos)
      << progressLine(held, "[5/5] poles kept");
  IdentifyReport paper;
  identifyModel({randomChambersLog(120.0)}, paperConfiguration(o), &paper);
  for (const auto& pp : paper.pairs) EXPECT_TRUE(pp.window_second_order.empty());
  o.local_order = 2;
  EXPECT_EQ(paperConfiguration(o).local_order, 1);  // the paper's first-order fits whatever plsa's were given
  IdentifyReport second;
  identifyModel({randomChambersLog(120.0)}, o, &second);
  for (const auto& s : second.pole_method_scores) EXPECT_EQ(s.method.find("order2"), std::string::npos) << s.method;
  for (const auto& pp : second.pairs) EXPECT_TRUE(pp.window_second_order.empty());
}

// An output no local fit can use (it reads noise alone) takes the poles the
// other outputs found, and says so. Alone, it gets the poles of the fits
// rejected only as badly determined or too weak for the noise, with a
// warning; an output whose fits give no physical pole at all is refused.
TEST(Pipeline, AnOutputWithoutUsableFitsTakesTheOtherOutputsPoles) {
  IdentifyReport rep;
  const DioPwlObfModel m =
      identifyModel({staircaseLog(Weakness::kWeakIsNoise)}, partitionOnly({"p_1"}, {"strong", "weak"}), &rep);
  ASSERT_EQ(m.poles.size(), 2u);
  EXPECT_EQ(m.poles[1][0].size(), m.poles[0][0].size());
  EXPECT_FALSE(rep.uncertain_poles);
  const auto said = [&](const IdentifyReport& r, const std::string& a, const std::string& b) {
    return std::any_of(r.lines.begin(), r.lines.end(), [&](const std::string& l) {
      return l.find(a) != std::string::npos && l.find(b) != std::string::npos;
    });
  };
  EXPECT_TRUE(said(rep, "no usable local fit for weak", "other outputs' poles"));
  EXPECT_TRUE(said(rep, "p_1 -> weak", "other outputs' poles"));

  IdentifyReport alone;
  const DioPwlObfModel noise_model =
      identifyModel({staircaseLog(Weakness::kWeakIsNoise)}, partitionOnly({"p_1"}, {"weak"}), &alone);
  EXPECT_TRUE(alone.uncertain_poles);
  EXPECT_TRUE(said(alone, "warning: no local fit passed its checks", "too weak for the noise"));
  EXPECT_TRUE(said(alone, "p_1 -> weak", "uncertain poles"));
  EXPECT_FALSE(said(alone, "no usable local fit for weak", "other outputs' poles")) << "there are no other outputs";
  for (const auto& p : noise_model.poles[0][0].poles()) EXPECT_TRUE(std::abs(p) < 1.0 && p.real() >= 0.0) << p;

  io::Log alternating = staircaseLog(Weakness::kWeakIsNoise);  // every fit's pole negative: nothing physical
  for (Eigen::Index k = 0; k < alternating.data.rows(); ++k) alternating.data(k, 4) = k % 2 == 0 ? 1.0 : -1.0;
  try {
    identifyModel({alternating}, partitionOnly({"p_1"}, {"weak"}));
    ADD_FAILURE() << "an output with no physical pole in any fit must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no usable local poles for output 'weak'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rejected:"), std::string::npos) << e.what();
  }
}

// Five chambers moving at random (two segments, say): more than an
// interpolated grid takes. Automatic scheduling keeps switched cells and
// says why; asked for the interpolated grid, the error names the option.
TEST(Pipeline, MoreInputsThanAnInterpolatedGridTakesKeepSwitchedCells) {
  const int inputs = 5;
  const Eigen::Index n = 9600;
  std::vector<std::string> columns = {"time_s"}, names;
  for (int j = 1; j <= inputs; ++j) names.push_back("p_" + std::to_string(j));
  columns.insert(columns.end(), names.begin(), names.end());
  columns.push_back("y");
  io::Log log = blankLog("five_chambers.csv", columns, n);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> level(0.0, 0.4);
  std::vector<double> u(inputs, 0.0);
  double y = 0.0;
  for (Eigen::Index k = 0; k < n; ++k) {
    if (k % 160 == 0)
      for (auto& v : u) v = level(rng);
    double drive = 0.0;
    for (int j = 0; j < inputs; ++j) drive += (j + 1) * u[static_cast<std::size_t>(j)];
    y = 0.95 * y + 0.05 * drive;
    log.data(k, 0) = static_cast<double>(k) * kDt;
    for (int j = 0; j < inputs; ++j) log.data(k, j + 1) = u[static_cast<std::size_t>(j)];
    log.data(k, inputs + 1) = y;
  }
  IdentifyOptions o = partitionOnly(names, {"y"});
  o.scheduling = SchedulingChoice::kAuto;
  IdentifyReport rep;
  const DioPwlObfModel m = identifyModel({log}, o, &rep);
  EXPECT_EQ(m.partition.scheduling(), Scheduling::kSwitched);
  EXPECT_TRUE(std::any_of(rep.lines.begin(), rep.lines.end(), [](const std::string& l) {
    return l.find("interpolated scheduling takes at most 4 scheduling inputs, and 5 inputs move") != std::string::npos;
  }));
  o.scheduling = SchedulingChoice::kInterpolated;
  test_fixtures::expectThrowContaining([&] { identifyModel({log}, o); }, "use --scheduling switched");
}
