#include "plsa/identify/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "identification_run.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/eval/validation.hpp"
#include "plsa/identify/local_fit.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/identify/segmentation.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::identify {
namespace {

// An option set by a cast from an integer outside its enum is refused by name.
template <class E>
void checkOption(E value) {
  PLSA_CHECK(optionName(value) != nullptr, std::string("identify: ") + OptionSpelling<E>::what + " " +
                                               std::to_string(static_cast<int>(value)) + " is none of " +
                                               optionChoices<E>());
}

}  // namespace

std::string formatPlaySet(const std::vector<PlayChannel>& set) {
  auto num = [](double v) { return fixedDecimals(v, 2); };
  std::string s = "{";
  for (std::size_t i = 0; i < set.size(); ++i) {
    s += i ? "," : "";
    if (set[i].slope == 0.0)
      s += num(set[i].width);
    else
      s += (set[i].width == 0.0 ? "" : num(set[i].width) + "+") + num(set[i].slope) + "u";
  }
  return s + "}";
}

std::vector<double> midpoints(const std::vector<double>& levels) {
  std::vector<double> b;
  for (std::size_t i = 1; i < levels.size(); ++i) b.push_back(0.5 * (levels[i - 1] + levels[i]));
  return b;
}

std::vector<double> quantileBreakpoints(std::vector<double> values, int levels) {
  PLSA_CHECK(levels >= 1, "quantileBreakpoints: need at least one level");
  std::sort(values.begin(), values.end());
  std::vector<double> b;
  for (int i = 1; i < levels; ++i) {
    const double v =
        values[static_cast<std::size_t>(std::lround(i / static_cast<double>(levels) * (values.size() - 1)))];
    if (b.empty() || v > b.back()) b.push_back(v);
  }
  return b;
}

namespace {

// The spread of the central 90% of the values (5% to 95% quantiles).
double centralSpread(const std::vector<double>& values) {
  const std::vector<double> ventiles = quantileBreakpoints(values, 20);
  return ventiles.size() < 2 ? 0.0 : ventiles.back() - ventiles.front();
}

}  // namespace

DioPwlObfModel identifyModel(const std::vector<io::Log>& logs, const IdentifyOptions& o, IdentifyReport* out) {
  IdentifyReport local;
  IdentificationRun run(o, out ? *out : local);
  return run.identify(logs);
}

IdentificationRun::IdentificationRun(const IdentifyOptions& options, IdentifyReport& report)
    : o(options), rep(report), fit_options(options.coefficients), last_line(Clock::now()) {}

// The paper's Table I, then plsa's structure search: each stage a function.
DioPwlObfModel IdentificationRun::identify(const std::vector<io::Log>& logs) {
  checkOptions(logs);
  readData(logs);
  fitLocalModels(logs);
  selectPoles();
  buildPartitions();
  listStructures();
  sampleForSearch();
  cutFolds();
  choosePoleMethod();
  chooseGridLevels();
  searchPlayAndScheduling();
  searchCoupling();
  searchPlayBank();
  searchScheduleLag();
  searchThreshold();
  refineJointly();
  searchSlowPole(searchOutputDrift());
  restoreAllData();
  return fitFinal();
}

void IdentificationRun::say(const std::string& line) {
  rep.lines.push_back(line);
  if (o.progress) o.progress(line);
  last_line = Clock::now();
}

PairPoles& IdentificationRun::pairAt(int in_i, int out_i) {
  return rep.pairs[static_cast<std::size_t>(out_i * ni + in_i)];
}

void IdentificationRun::checkOptions(const std::vector<io::Log>& logs) const {
  PLSA_CHECK(!logs.empty(), "identify: no logs given");
  PLSA_CHECK(!o.inputs.empty() && !o.outputs.empty(), "identify: need at least one input and one output column");
  PLSA_CHECK(o.poles_per_pair >= 1 && o.poles_per_pair <= 20,  // 2^31 - 1 grew to 22 GB before any check
             "identify: poles per pair must be 1 to 20, got " + std::to_string(o.poles_per_pair));
  refuseRepeatedColumns();
  PLSA_CHECK(!o.angle_unit || *o.angle_unit == "deg" || *o.angle_unit == "rad",
             "identify: the angle unit must be deg or rad, got '" + o.angle_unit.value_or("") + "'");
  PLSA_CHECK(o.quantile_levels >= 0 && o.quantile_levels <= 12,
             "identify: quantile levels must be 0 (automatic) or 1..12, got " + std::to_string(o.quantile_levels));
  PLSA_CHECK(
      o.play_refine_evaluations >= 0 && o.play_refine_evaluations <= 10000,
      "identify: play refinement evaluations must be in 0..10000, got " + std::to_string(o.play_refine_evaluations));
  PLSA_CHECK(std::isfinite(o.progress_interval_s) && o.progress_interval_s >= 0,
             "identify: the progress interval must be a finite number of seconds >= 0");
  PLSA_CHECK(o.search_max_samples >= 0, "identify: the search's sample size must be >= 0 (0: every sample)");
  PLSA_CHECK(std::isfinite(o.search_window_s) && o.search_window_s > 0 && o.search_window_s < 1e9,
             "identify: the search's windows must last a positive, finite number of seconds");
  PLSA_CHECK(std::isfinite(o.step_threshold) && o.step_threshold > 0,
             "identify: the step threshold must be a positive, finite reference change");
  PLSA_CHECK(std::isfinite(o.step_threshold_share) && o.step_threshold_share > 0 && o.step_threshold_share < 1,
             "identify: the step threshold's share must be a fraction of the references' largest level in (0, 1)");
  PLSA_CHECK(std::isfinite(o.play_bank_min_gain) && o.play_bank_min_gain >= 0,
             "identify: the least gain that keeps a bank of plays must be finite and >= 0 (fit points)");
  for (const auto& bank : o.play_bank_candidates)
    PLSA_CHECK(bank.size() >= 2,
               "identify: a bank of plays needs at least two channels (a single one is a play "
               "set: play_candidates, --play)");
  PLSA_CHECK(!std::isnan(o.window_poles_below), "identify: window_poles_below is NaN");
  PLSA_CHECK(!std::isnan(o.second_order_windows_below), "identify: second_order_windows_below is NaN");
  checkOption(o.pole_method);
  checkOption(o.scheduling);
  checkOption(o.output_drift);
  checkOption(o.cv_layout);
}

// A column named twice among the inputs and outputs, or the time column as
// one of them: refused before any work (the model file would refuse it after
// the whole identification).
void IdentificationRun::refuseRepeatedColumns() const {
  std::vector<std::string> named = o.inputs;
  named.insert(named.end(), o.outputs.begin(), o.outputs.end());
  for (std::size_t i = 0; i < named.size(); ++i) {
    PLSA_CHECK(named[i] != io::standard_columns::kTime,
               "identify: '" + named[i] + "' is the logs' time, not an input or output (check --inputs, --outputs)");
    for (std::size_t j = 0; j < i; ++j)
      PLSA_CHECK(named[i] != named[j], "identify: column '" + named[i] + "' is named twice among the inputs and " +
                                           "outputs (check --inputs, --outputs)");
  }
}

// Data and sample time; every log must agree.
// The output frame as given (IdentifyOptions::output_frame), the tip
// frame's angle unit given or read as chooseAngleUnit reads it.
OutputFrameChoice IdentificationRun::givenOutputFrame() const {
  OutputFrameChoice c;
  c.frame = *o.output_frame;
  c.reason = std::string("output frame ") + toString(c.frame) + " as given";
  if (c.frame != OutputFrame::kTipCartesian) return c;
  PLSA_CHECK(o.outputs.size() == 2,
             "identify: the tip_cartesian output frame needs exactly two outputs (bending, steering), got " +
                 std::to_string(o.outputs.size()));
  c.angle_unit = chooseAngleUnit(o.outputs, Y, o.angle_unit, c.angle_unit_reason);
  return c;
}

namespace {

// The command column that steps input j by default: cmd_N for a chamber's
// own columns (p_N, cmd_N), so that --inputs p_2 alone steps on cmd_2;
// cmd_<j+1> for an input of another name.
std::string defaultCommandReference(const std::string& input, std::size_t j) {
  namespace columns = io::standard_columns;
  for (int n = 1; n <= columns::kChambers; ++n)
    if (input == columns::pressure(n) || input == columns::command(n)) return columns::command(n);
  return columns::command(static_cast<int>(j) + 1);
}

}  // namespace

void IdentificationRun::readData(const std::vector<io::Log>& logs) {
  std::vector<std::string> reference = o.reference;
  if (reference.empty()) {
    namespace columns = io::standard_columns;
    const bool have_cmd = logs[0].hasColumn(columns::command(1)) && o.inputs.size() <= columns::kChambers;
    for (std::size_t j = 0; j < o.inputs.size(); ++j)
      reference.push_back(have_cmd ? defaultCommandReference(o.inputs[j], j) : o.inputs[j]);
    references_are_inputs = !have_cmd;
  }
  if (reference.size() != o.inputs.size()) {
    std::string names;
    for (const auto& r : reference) names += (names.empty() ? "" : ", ") + r;
    throw std::invalid_argument("identify: the reference columns (" + names + ") are " +
                                std::to_string(reference.size()) + " for " + std::to_string(o.inputs.size()) +
                                " inputs; name one per input, in the inputs' order");
  }
  for (const auto& log : logs) {
    if (o.refuse_outliers) {
      std::vector<std::string> columns = o.inputs;
      columns.insert(columns.end(), o.outputs.begin(), o.outputs.end());
      const std::string outlier = grossOutlier(log, columns);
      if (!outlier.empty())
        throw std::invalid_argument(outlier +
                                    ": a glitch would shape the whole model; remove the sample (or "
                                    "identify with --keep-outliers)");
    }
    const double t = io::checkedSampleTime(log, io::standard_columns::kTime, o.max_gap_factor);
    if (dt == 0.0) dt = t;
    if (!io::sameSampleTime(t, dt))
      throw std::invalid_argument(log.source + ": sample time " + std::to_string(t) +
                                  " s differs from the first log's " + std::to_string(dt) + " s");
    U.push_back(log.columnsOf(o.inputs));
    Y.push_back(log.columnsOf(o.outputs));
    Ref.push_back(log.columnsOf(reference));
    times.push_back(log.column(io::standard_columns::kTime));
  }
  refuseUnfittableMagnitudes();
  refuseStillColumns();
  refuseRepeatedLogs(logs);
  for (double tau : o.slow_pole_candidates) {  // under dt, exp(-dt / tau) would be 0 or a fast pole, not a slow one
    PLSA_CHECK(tau == 0.0 || (std::isfinite(tau) && tau > 0.0),
               "identify: --slow-pole " + formatNumber(tau) + ": a time constant is 0 (none) or a finite time in s");
    PLSA_CHECK(tau == 0.0 || tau >= dt, "identify: --slow-pole " + formatNumber(tau) + " s is shorter than the " +
                                            formatNumber(dt) + " s sample time (a slow pole lasts many samples)");
  }
  // Local fits see the outputs in the model's frame; every other step takes them as logged.
  rep.output_frame = o.output_frame ? givenOutputFrame() : chooseOutputFrame(o.outputs, Y, o.angle_unit);
  frame = rep.output_frame.frame;
  Ym = toModelFrame(frame, Y, frame == OutputFrame::kAsLogged ? 1.0 : radiansPerAngleUnit(rep.output_frame.angle_unit));
  total = 0;
  for (const auto& u : U) total += u.rows();
  say("[1/5] data: " + std::to_string(logs.size()) + " log(s), " + std::to_string(total) + " samples at " +
      formatNumber(1.0 / dt) + " Hz");
  if (!o.output_frame) say("[1/5] " + rep.output_frame.reason);
  if (frame == OutputFrame::kTipCartesian)
    say("[1/5] outputs: " + o.outputs[0] + " and " + o.outputs[1] + " as a tip's bending and steering angles in " +
        rep.output_frame.angle_unit +
        (o.output_frame ? " (" + rep.output_frame.angle_unit_reason + ")" : std::string()) +
        "; the model "
        "runs on " +
        o.outputs[0] + " cos(" + o.outputs[1] + ") and " + o.outputs[0] + " sin(" + o.outputs[1] + ")");
  ni = static_cast<int>(o.inputs.size());
  no = static_cast<int>(o.outputs.size());
  min_len = static_cast<Eigen::Index>(std::lround(1.0 / dt));  // a local step needs >= 1 s
  stepResolution();
}

// The reference change that counts as a step, in the logs' units:
// step_threshold, or step_threshold_share of the references' largest level
// when that is smaller, so that a log in MPa, whose 0.005 MPa steps an
// absolute 0.005 would read as still, is cut where the same log in bar is.
void IdentificationRun::stepResolution() {
  double top = 0.0;
  for (const auto& r : Ref)
    if (r.size() > 0) top = std::max(top, r.cwiseAbs().maxCoeff());
  PLSA_CHECK(std::isfinite(top), "identify: a reference column holds a value that is not finite");
  step = std::max(std::min(o.step_threshold, o.step_threshold_share * top), std::numeric_limits<double>::min());
}

// Steps 1-2: local data sets and local LTI fits: the steps first, then local
// windows for outputs the steps leave short of poles.
void IdentificationRun::fitLocalModels(const std::vector<io::Log>& logs) {
  rep.pairs.clear();
  for (int out_i = 0; out_i < no; ++out_i)
    for (int in_i = 0; in_i < ni; ++in_i) {
      PairPoles pp;
      pp.input = in_i;
      pp.output = out_i;
      rep.pairs.push_back(pp);
    }
  fitStepSegments(logs);
  if (rep.segments == 0 && references_are_inputs) stepsFromPlateaus(logs);
  const std::vector<WindowUse> windows = chooseWindows();
  if (rep.used_windows || !rep.window_candidate_outputs.empty()) fitLocalWindows(logs, windows);
  int usable = 0, rejected = 0;
  for (const auto& pp : rep.pairs) {
    usable += static_cast<int>(pp.identified.size() + pp.window_identified.size());
    rejected += pp.rejected;
  }
  say("[2/5] local LTI fits: " + std::to_string(rep.segments) + " step segments" + windowsNote() + ", " +
      std::to_string(usable) + " poles kept, " + std::to_string(rejected) +
      " fits rejected (unstable, badly determined or too small for the noise)");
}

// Per output, what local windows do: an output whose steps gave no usable
// pole takes its poles from them; for one whose steps gave fewer than a
// bank places they are fitted too, kept apart (PairPoles::window_identified)
// for the structure search to try with the steps' when the steps' model
// fails (choosePoleMethod).
std::vector<IdentificationRun::WindowUse> IdentificationRun::chooseWindows() {
  std::vector<std::size_t> step_poles(static_cast<std::size_t>(no), 0);
  for (const auto& pp : rep.pairs) step_poles[static_cast<std::size_t>(pp.output)] += pp.identified.size();
  std::vector<WindowUse> use(static_cast<std::size_t>(no), WindowUse::kNone);
  rep.window_outputs.clear();
  rep.window_candidate_outputs.clear();
  for (int out_i = 0; out_i < no; ++out_i) {
    const auto oo = static_cast<std::size_t>(out_i);
    if (step_poles[oo] == 0) {
      use[oo] = WindowUse::kInstead;
      rep.window_outputs.push_back(o.outputs[oo]);
    } else if (step_poles[oo] < static_cast<std::size_t>(o.poles_per_pair)) {
      use[oo] = WindowUse::kCandidate;
      rep.window_candidate_outputs.push_back(o.outputs[oo]);
    }
  }
  rep.used_windows = !rep.window_outputs.empty();
  rep.staircase = rep.window_outputs.size() < o.outputs.size();
  return use;
}

// The progress line's note on the windows (empty without them).
std::string IdentificationRun::windowsNote() const {
  std::string note;
  if (rep.used_windows) {
    note = " (no usable step responses";
    if (rep.staircase) {
      note += " for";
      for (const auto& name : rep.window_outputs) note += " " + name;
    }
    note += ": local windows of " + formatNumber(o.window_s) + " s instead)";
  }
  if (!rep.window_candidate_outputs.empty()) {
    note += " (fewer usable step poles than the " + std::to_string(o.poles_per_pair) + " to place for";
    for (const auto& name : rep.window_candidate_outputs) note += " " + name;
    note += ": local windows of " + formatNumber(o.window_s) + " s fitted, their poles tried if the steps' fail)";
  }
  return note;
}

// MISO fits on local windows give the outputs `use` names their poles (or a
// candidate's).
void IdentificationRun::fitLocalWindows(const std::vector<io::Log>& logs, const std::vector<WindowUse>& use) {
  for (auto& pp : rep.pairs)
    if (use[static_cast<std::size_t>(pp.output)] == WindowUse::kInstead) {  // the steps' rejections no longer tell
      pp.rejected = 0;
      pp.rejections.clear();
    }
  const auto w = static_cast<Eigen::Index>(std::lround(o.window_s / dt));
  for (std::size_t r = 0; r < logs.size(); ++r)
    for (Eigen::Index b = 1; b + w <= U[r].rows(); b += w)
      for (int out_i = 0; out_i < no; ++out_i) {
        const WindowUse how = use[static_cast<std::size_t>(out_i)];
        if (how == WindowUse::kNone) continue;
        // Fit y on each input separately is ill-posed with all moving: use the strongest input.
        Eigen::Index best = 0;
        double spread = -1;
        for (int in_i = 0; in_i < ni; ++in_i) {
          const auto seg = U[r].col(in_i).segment(b, w);
          const double s = seg.maxCoeff() - seg.minCoeff();
          if (s > spread) {
            spread = s;
            best = in_i;
          }
        }
        const LocalFit f = fitLocalModel(U[r].col(best).segment(b, w), Ym[r].col(out_i).segment(b, w),
                                         U[r](b - 1, best), Ym[r](b - 1, out_i), o.local_order);
        // At first order, random excitation's windows can give slow poles
        // only: the same window at second order is a further candidate.
        const bool second = how == WindowUse::kInstead && o.local_order == 1 &&
                            o.second_order_windows_below > -std::numeric_limits<double>::infinity();
        const LocalFit f2 = second ? fitLocalModel(U[r].col(best).segment(b, w), Ym[r].col(out_i).segment(b, w),
                                                   U[r](b - 1, best), Ym[r](b - 1, out_i), 2)
                                   : LocalFit{};
        for (int in_i = 0; in_i < ni; ++in_i) {
          PairPoles& pp = pairAt(in_i, out_i);
          if (f2.usable) pp.window_second_order.insert(pp.window_second_order.end(), f2.poles.begin(), f2.poles.end());
          auto& into = how == WindowUse::kInstead ? pp.identified : pp.window_identified;
          if (f.usable)
            into.insert(into.end(), f.poles.begin(), f.poles.end());
          else if (f.uncertain && how == WindowUse::kInstead)
            pp.uncertain.insert(pp.uncertain.end(), f.poles.begin(), f.poles.end());
          if (!f.usable && in_i == 0 && how == WindowUse::kInstead) {
            ++pp.rejected;
            pp.rejections.push_back(logs[r].source + " window at " + std::to_string(b) + ": " + f.reason);
          }
        }
      }
}

// An output's local fits were all rejected: the error, with the first reasons.
[[noreturn]] void IdentificationRun::noUsablePoles(int out_i) const {
  std::string why;
  int shown = 0;
  for (const auto& p : rep.pairs)
    for (const auto& r : p.rejections)
      if (p.output == out_i && shown++ < 3) why += "\n  rejected: " + r;
  throw std::runtime_error("identify: no usable local poles for output '" + o.outputs[static_cast<std::size_t>(out_i)] +
                           "' or any other (" + std::to_string(rep.segments) + " step segments, all fits rejected)" +
                           why);
}

// No local fit passed its checks: the poles of those rejected only as badly
// determined or too weak for the noise, the last resort before refusing.
std::vector<std::complex<double>> IdentificationRun::uncertainPoles() {
  std::vector<std::complex<double>> poles;
  for (const PairPoles& pp : rep.pairs) poles.insert(poles.end(), pp.uncertain.begin(), pp.uncertain.end());
  if (poles.empty()) return poles;
  rep.uncertain_poles = true;
  say("[3/5] warning: no local fit passed its checks; the poles come from the " + std::to_string(poles.size()) +
      " physical ones of fits rejected only as badly determined or too weak for the noise: the outputs are weak "
      "against their noise, and the model's fits will show it");
  return poles;
}

// Partition: the experiment's reference levels, else a quantile grid.
void IdentificationRun::buildPartitions() {
  all_ref.resize(total, ni);
  all_u.resize(total, ni);
  {
    Eigen::Index row = 0;
    for (std::size_t r = 0; r < U.size(); ++r) {
      all_ref.middleRows(row, Ref[r].rows()) = Ref[r];
      all_u.middleRows(row, U[r].rows()) = U[r];
      row += U[r].rows();
    }
  }
  grid_plan = gridPlan();
  makePartitions(true);
  top_level = std::max(1e-12, all_u.maxCoeff());
}

void IdentificationRun::makePartitions(bool announce) {
  partitions.clear();
  std::vector<bool> schedulings;  // interpolated?
  if (o.scheduling != SchedulingChoice::kSwitched) schedulings.push_back(true);
  if (o.scheduling != SchedulingChoice::kInterpolated) schedulings.push_back(false);
  for (const bool interpolated : schedulings) addPartition(interpolated, grid_plan, announce);
  PLSA_CHECK(!partitions.empty(), "identify: no partition could be built");
}

// The staircase's reference levels, or a quantile grid when the logs hold
// no designed levels.
IdentificationRun::GridPlan IdentificationRun::gridPlan() const {
  GridPlan grid;
  grid.levels = referenceLevels(all_ref, step, min_len);
  // A designed staircase holds a few reference levels; measured data that
  // merely pauses holds hundreds: that is no grid, use quantiles instead.
  constexpr std::size_t kMaxDesignedLevels = 8;
  // The design is the reference's: outputs too weak for their step fits (a
  // nearly straight segment, a noisy sensor) do not make it less designed.
  grid.designed = rep.segments > 0;
  for (const auto& lv : grid.levels) grid.designed = grid.designed && lv.size() <= kMaxDesignedLevels + 1;
  if (grid.designed) return grid;
  grid.moving = quantileInputs();
  grid.quantile_levels = quantileLevels(grid.moving.size());
  return grid;
}

// The inputs a quantile grid schedules on: not those whose central 90%
// spans no more than a step, or a twentieth of the widest input's (an unused
// chamber's sensor noise).
std::vector<int> IdentificationRun::quantileInputs() const {
  std::vector<double> spread;
  for (int in_i = 0; in_i < ni; ++in_i) {
    const Eigen::VectorXd col = all_u.col(in_i);
    spread.push_back(centralSpread(std::vector<double>(col.data(), col.data() + col.size())));
  }
  const double widest = spread.empty() ? 0.0 : *std::max_element(spread.begin(), spread.end());
  std::vector<int> inputs;
  for (int in_i = 0; in_i < ni; ++in_i)
    if (spread[static_cast<std::size_t>(in_i)] > std::max(step, 0.05 * widest)) inputs.push_back(in_i);
  return inputs;
}

// IdentifyOptions::quantile_levels, or with 0 the automatic choice: 3, or 2
// when 3 would leave under kMinSecondsPerRegion of data per region.
int IdentificationRun::quantileLevels(std::size_t inputs) const {
  if (o.quantile_levels > 0) return o.quantile_levels;
  const double seconds = static_cast<double>(total) * dt;
  const double regions = std::pow(double{IdentifyOptions::kAutoQuantileLevels}, static_cast<double>(inputs));
  return seconds / regions >= IdentifyOptions::kMinSecondsPerRegion ? IdentifyOptions::kAutoQuantileLevels
                                                                    : IdentifyOptions::kShortDataQuantileLevels;
}

std::string IdentifyOptions::autoQuantileRule() {
  return std::to_string(kAutoQuantileLevels) + ", then one level finer at a time, up to " +
         std::to_string(kMaxScoredQuantileLevels) + ", while the finer grid has " + formatNumber(kMinSecondsPerRegion) +
         " s of data per region on average and scores " + formatNumber(kGridLevelsMargin) +
         " points higher held out; or " + std::to_string(kShortDataQuantileLevels) + " when " + shortDataReason();
}

std::string IdentifyOptions::shortDataReason() {
  return std::to_string(kAutoQuantileLevels) + " would leave under " + formatNumber(kMinSecondsPerRegion) +
         " s of data per region";
}

// One partition (interpolated nodes or switched cells) over the scheduling
// inputs the grid plan gives.
void IdentificationRun::addPartition(bool interpolated, const GridPlan& grid, bool announce) {
  std::vector<int> sched;
  std::vector<std::vector<double>> bps;
  for (int in_i = 0; in_i < ni && grid.designed; ++in_i) {
    std::vector<double> lv;
    for (double l : grid.levels[static_cast<std::size_t>(in_i)])
      if (l > step) lv.push_back(l);  // the vented level is not a reference pressure
    if (lv.size() >= 2) {
      sched.push_back(in_i);
      bps.push_back(interpolated ? lv : midpoints(lv));
    }
  }
  for (const int in_i : grid.moving) {
    const Eigen::VectorXd col = all_u.col(in_i);
    // Switched: cells between quantiles; interpolated: nodes at the cells' medians.
    auto b = quantileBreakpoints(std::vector<double>(col.data(), col.data() + col.size()),
                                 interpolated ? 2 * grid.quantile_levels : grid.quantile_levels);
    if (interpolated) {
      std::vector<double> nodes;
      for (std::size_t i = 0; i < b.size(); i += 2) nodes.push_back(b[i]);
      b = nodes;
    }
    if (!b.empty()) {
      sched.push_back(in_i);
      bps.push_back(b);
    }
  }
  if (interpolated && sched.size() > static_cast<std::size_t>(PwlPartition::kMaxInterpolatedInputs)) {
    const std::string why = "interpolated scheduling takes at most " +
                            std::to_string(PwlPartition::kMaxInterpolatedInputs) + " scheduling inputs, and " +
                            std::to_string(sched.size()) + " inputs move";
    if (o.scheduling != SchedulingChoice::kAuto)
      throw std::invalid_argument("identify: " + why + "; use --scheduling switched");
    if (announce) say("[4/5] " + why + ": switched cells only (input-side scheduling needs the interpolated grid)");
    return;
  }
  partitions.push_back(interpolated ? PwlPartition::interpolated(sched, bps, o.direction_split)
                                    : PwlPartition(sched, bps, o.direction_split));
  if (partitions.back().regionCount() > kMaxRegions)
    throw std::invalid_argument(
        "identify: the partition would have " + std::to_string(partitions.back().regionCount()) + " regions (limit " +
        std::to_string(kMaxRegions) + "); use fewer --levels or scheduling inputs, or no direction split");
  requireDataForPartition(partitions.back(), grid);
  model.partition = partitions.back();
  model.input_min = all_u.minCoeff();
  model.input_max = all_u.maxCoeff();
  model.input_ranges.clear();
  for (Eigen::Index c = 0; c < all_u.cols(); ++c)
    model.input_ranges.push_back({all_u.col(c).minCoeff(), all_u.col(c).maxCoeff()});
  if (announce) say(partitionLine(interpolated, grid, sched, bps));
}

// Each region's coefficients need samples: with more coefficients than
// samples the fit is underdetermined, and the structure search's solves
// (cubic in the coefficients) run for hours before saying so.
void IdentificationRun::requireDataForPartition(const PwlPartition& partition, const GridPlan& grid) const {
  const long long regions = partition.regionCount();
  const long long coefficients = regions * ni * o.poles_per_pair;  // per output, one play channel per input
  if (coefficients <= static_cast<long long>(total)) return;
  const std::string levels = grid.designed
                                 ? std::string("the logs' reference levels give")
                                 : "a quantile grid of " + std::to_string(grid.quantile_levels) + " levels gives";
  throw std::invalid_argument("identify: " + levels + " " + std::to_string(regions) + " regions, so " +
                              std::to_string(coefficients) + " coefficients per output (regions x inputs x poles), " +
                              "more than the " + std::to_string(total) +
                              " samples can determine; use fewer --levels or --poles, or more data");
}

// The [4/5] line: the partition, its breakpoints, and why its grid.
std::string IdentificationRun::partitionLine(bool interpolated, const GridPlan& grid, const std::vector<int>& sched,
                                             const std::vector<std::vector<double>>& bps) const {
  std::string s = std::string("[4/5] partition (") + (interpolated ? "interpolated" : "switched") +
                  "): " + std::to_string(model.partition.regionCount()) + " regions";
  for (std::size_t i = 0; i < sched.size(); ++i) {
    s += (i ? "; " : " over ") + o.inputs[static_cast<std::size_t>(sched[i])] + (interpolated ? " nodes" : " split at");
    for (double b : bps[i]) s += " " + fixedDecimals(b, 4);
  }
  if (!grid.designed)
    s += " (quantile grid of " + std::to_string(grid.quantile_levels) +
         " levels: the logs hold no designed reference levels" +
         (grid.scored ? "; kept by held-out score"
          : o.quantile_levels > 0 || grid.quantile_levels == IdentifyOptions::kAutoQuantileLevels
              ? std::string()
              : "; " + IdentifyOptions::shortDataReason()) +
         ")";
  if (o.direction_split) s += "; split by direction of change";
  return s;
}

}  // namespace plsa::identify
