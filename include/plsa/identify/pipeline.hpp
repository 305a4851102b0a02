// The paper's Table I from logs to a model: segment, local LTI fits, pole
// clustering per input-output pair, OBF banks, DIO-PWL partition, coefficients.
// Every stage reports what it did and what it rejected.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/identify/output_frame_choice.hpp"
#include "plsa/identify/pole_clustering.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::identify {

/// A value of a training column this far from the column's median, in
/// widths of its 1-99% band, is taken for a glitch, not a measurement.
inline constexpr double kGrossOutlierBands = 50.0;

/// The first sample of `names` in `log` that lies more than
/// kGrossOutlierBands band widths from its column's median, as
/// "FILE: data row R, column 'C': V lies N band widths from ..."; empty when
/// there is none (or a column's band has no width).
std::string grossOutlier(const io::Log& log, const std::vector<std::string>& names);

/// Whether column `j` holds one value (to 1e-12 of its size) in every sample
/// of every block: a column that never moves.
bool holdsOneValue(const std::vector<Eigen::MatrixXd>& blocks, Eigen::Index j);

/// How each input-output pair's poles are chosen from its local poles
/// (pole_clustering.hpp).
enum class PoleMethod { kFkcm, kFuzzyCMeans, kKMeans, kGlobalRho, kAuto };
/// Which scheduling structures identification tries (IdentifyOptions::scheduling).
enum class SchedulingChoice { kAuto, kInterpolated, kSwitched, kInputSide };
/// Whether a sensor drift linear in time is taken out of the training
/// outputs (IdentifyOptions::output_drift).
enum class OutputDriftChoice { kAuto, kOn, kOff };
/// How cross-validation cuts the training logs (IdentifyOptions::cv_layout).
enum class CvLayout { kInterleaved, kContiguous };
/// How the slow pole's coefficients are fitted (IdentifyOptions::slow_pole_form).
enum class SlowPoleForm { kTied, kFree };
/// What the tied slow fractions are fitted on (IdentifyOptions::slow_fraction_fit).
enum class SlowFractionFit { kLevel, kIncrements };

/// The spellings of an option's values, as the command line, the reports and
/// the docs use them, and the option's name in messages.
template <class E>
struct OptionSpelling;
template <>
struct OptionSpelling<PoleMethod> {
  static constexpr const char* what = "pole method";
  static constexpr std::array<std::pair<PoleMethod, const char*>, 5> values{{{PoleMethod::kFkcm, "fkcm"},
                                                                             {PoleMethod::kFuzzyCMeans, "fcm"},
                                                                             {PoleMethod::kKMeans, "kmeans"},
                                                                             {PoleMethod::kGlobalRho, "global"},
                                                                             {PoleMethod::kAuto, "auto"}}};
};
template <>
struct OptionSpelling<SchedulingChoice> {
  static constexpr const char* what = "scheduling";
  static constexpr std::array<std::pair<SchedulingChoice, const char*>, 4> values{
      {{SchedulingChoice::kAuto, "auto"},
       {SchedulingChoice::kInterpolated, "interpolated"},
       {SchedulingChoice::kSwitched, "switched"},
       {SchedulingChoice::kInputSide, "input"}}};
};
template <>
struct OptionSpelling<OutputDriftChoice> {
  static constexpr const char* what = "output drift";
  static constexpr std::array<std::pair<OutputDriftChoice, const char*>, 3> values{
      {{OutputDriftChoice::kAuto, "auto"}, {OutputDriftChoice::kOn, "on"}, {OutputDriftChoice::kOff, "off"}}};
};
template <>
struct OptionSpelling<SlowPoleForm> {
  static constexpr const char* what = "slow pole form";
  static constexpr std::array<std::pair<SlowPoleForm, const char*>, 2> values{
      {{SlowPoleForm::kTied, "tied"}, {SlowPoleForm::kFree, "free"}}};
};
template <>
struct OptionSpelling<SlowFractionFit> {
  static constexpr const char* what = "slow fraction fit";
  static constexpr std::array<std::pair<SlowFractionFit, const char*>, 2> values{
      {{SlowFractionFit::kLevel, "level"}, {SlowFractionFit::kIncrements, "increments"}}};
};
template <>
struct OptionSpelling<CvLayout> {
  static constexpr const char* what = "cross-validation layout";
  static constexpr std::array<std::pair<CvLayout, const char*>, 2> values{
      {{CvLayout::kInterleaved, "interleaved"}, {CvLayout::kContiguous, "contiguous"}}};
};

/// The value's spelling; nullptr for a value outside the enum (a cast).
template <class E>
const char* optionName(E value) noexcept {
  for (const auto& [e, name] : OptionSpelling<E>::values)
    if (e == value) return name;
  return nullptr;
}

/// The values' spellings in order, e.g. "auto, on or off".
template <class E>
std::string optionChoices() {
  std::string list;
  const auto& values = OptionSpelling<E>::values;
  for (std::size_t i = 0; i < values.size(); ++i)
    list += (i == 0 ? "" : i + 1 == values.size() ? " or " : ", ") + std::string(values[i].second);
  return list;
}

/// The value spelt `name`; throws std::invalid_argument naming the option and its choices.
template <class E>
E parseOption(const std::string& name) {
  for (const auto& [e, spelling] : OptionSpelling<E>::values)
    if (name == spelling) return e;
  throw std::invalid_argument(std::string(OptionSpelling<E>::what) + " '" + name + "': expected " + optionChoices<E>());
}

struct IdentifyOptions {
  std::vector<std::string> inputs = io::standard_columns::pressures();
  std::vector<std::string> outputs = io::standard_columns::tipAngles();
  /// tip_cartesian: the two outputs are a tip's bending and steering angles
  /// (deg or rad: angle_unit) and the model runs on the tip direction's components (output_frame.hpp).
  /// Unset (the default): chosen from the outputs' names and data
  /// (chooseOutputFrame), the choice and its reason in the progress lines
  /// and IdentifyReport::output_frame.
  std::optional<OutputFrame> output_frame;
  /// The unit of a tip's bending and steering angles, "deg" or "rad", for
  /// the tip frame; unset (the default): read from the names, else from the
  /// data's range (chooseAngleUnit). The model's output_unit.
  std::optional<std::string> angle_unit;
  /// Piecewise-constant references to segment on; empty: cmd_1..3 when
  /// present, else the inputs, or, when those step nowhere as logged (their
  /// noise), the plateaus they hold (plateauReference).
  std::vector<std::string> reference;
  int poles_per_pair = 5;
  int local_order = 1;
  /// How each pair's local poles become its basis poles. "auto": FKcM (the
  /// paper's) and fuzzy c-means both, the structure search's first stage
  /// keeping the one whose model scores higher on held-out data (FKcM unless
  /// fuzzy c-means scores higher; FKcM alone with clustering.complex_pairs).
  PoleMethod pole_method = PoleMethod::kAuto;
  ClusteringOptions clustering;
  /// Levels per scheduling input when the log has no staircase (quantile
  /// grid). 0 (default): the automatic count (3, or 2 when the training
  /// data give under kMinSecondsPerRegion per region of 3 levels: two
  /// minutes of three chambers, 27 regions of under 5 s each; 2 is kept),
  /// then, the structure search's second stage
  /// (IdentifyReport::grid_level_scores), one level finer at a time up to
  /// kMaxScoredQuantileLevels while the finer grid's regions get
  /// kMinSecondsPerRegion of the scored data on average and it scores
  /// kGridLevelsMargin points above the best so far, held out
  /// play_selection_horizon steps ahead. A number given is kept.
  int quantile_levels = 0;
  /// quantile_levels 0: score the level counts (true) or take the automatic
  /// count unscored (false: the paper's configuration, which has no such stage).
  bool score_grid_levels = true;
  static constexpr int kAutoQuantileLevels = 3;
  static constexpr int kShortDataQuantileLevels = 2;
  static constexpr int kMaxScoredQuantileLevels = 5;
  static constexpr double kMinSecondsPerRegion = 10.0;
  static constexpr double kGridLevelsMargin = 0.1;  ///< fit points
  /// quantile_levels 0's rule in words, for help texts: "3 (or 2 when ...),
  /// then one level finer at a time, up to 5, while ...".
  static std::string autoQuantileRule();
  /// Why the rule takes kShortDataQuantileLevels: "3 would leave under 10 s
  /// of data per region".
  static std::string shortDataReason();
  bool direction_split = false;
  /// "interpolated" (coefficients blended between grid nodes), "switched"
  /// (the paper's PWL), "input" (interpolated on the input side:
  /// DioPwlObfModel::schedule_side) or "auto" (all three tried, chosen by
  /// blocked cross-validation; input side only without a direction split).
  SchedulingChoice scheduling = SchedulingChoice::kAuto;
  /// A reference change above step_threshold (in the logs' units: 5 mbar
  /// in bar) is a step, or above step_threshold_share of the references'
  /// largest level when that is smaller (a log in MPa is cut as in bar).
  double step_threshold = 0.005;
  double step_threshold_share = 0.025;
  double max_gap_factor = io::kToleratedGapFactor;  ///< tolerated sample-time gap (dropped samples)
  /// Refuse training data with a gross outlier (grossOutlier()); false fits them as they are.
  bool refuse_outliers = true;
  double window_s = 8.0;  ///< local windows when the log has no steps
  /// An output whose steps give fewer usable poles than a bank places (one
  /// step's pole, say) takes a bank of them repeated; local windows' poles
  /// with the steps' are a second candidate, scored against them, when the
  /// steps' best model scores below this on held-out data (the mean of its
  /// 40-step and simulation fits, in percent). Default 0: only when the
  /// steps' model is worse than the outputs' mean (on the real arm's
  /// leave-one-out the repeated pole generalises better than the windows',
  /// though the search's own held-out scores prefer the windows'); 100:
  /// always; -inf: never.
  double window_poles_below = 0.0;
  /// An output without a usable step response (random excitation) takes its
  /// poles from local windows; fitted at first order (local_order 1, the
  /// paper's) they can give slow poles only. The same windows fitted at
  /// second order are two more pole candidates ("+order2"), scored with the
  /// others, when the best first-order candidate scores below this on
  /// held-out data (percent, as window_poles_below). 100: always; -inf: never
  /// (paperConfiguration).
  double second_order_windows_below = 100.0;
  CoefficientFitOptions coefficients;
  /// Hysteresis memory: candidate sets of play channels. A channel's width is
  /// a fraction of the input's range in the training data, its slope a
  /// fraction of the input's level (a band that grows with the pressure). The
  /// set whose model predicts held-out blocks of the training data best k
  /// steps ahead (blocked cross-validation) is kept. {{0}} alone gives the
  /// paper's model.
  /// Default: one channel per input, fixed or growing, its size chosen.
  /// Several channels per set are possible; the default's banks of several
  /// widths are play_bank_candidates, scored on the chosen scheduling only.
  std::vector<std::vector<PlayChannel>> play_candidates = {
      {0.0}, {0.02}, {0.04}, {0.07}, {0.1}, {0.15}, {0.2}, {{0.0, 0.08}}, {{0.0, 0.12}}, {{0.0, 0.16}}, {{0.0, 0.2}}};
  /// Then, on the chosen scheduling, every play set again with its channels
  /// coupled to the other inputs (InputShaping::coupling), kappa
  /// given as a fraction of the largest training input level: 0.3 lets a
  /// full neighbour cut a chamber's level by 30%. Empty: no coupling.
  std::vector<double> play_coupling_candidates = {0.15, 0.3};
  /// Then banks of plays, several widths per input (a Prandtl-Ishlinskii
  /// operator: a width-0 channel is its linear part, each play's weight is
  /// fitted by the same least squares), each tried on the chosen scheduling,
  /// uncoupled and with the chosen coupling, against the chosen set. A bank
  /// of three multiplies the regressors of every later fit by three, so it
  /// is scored here, not with every scheduling and coupling as the sets
  /// above are, and the best is kept only when its held-out gain exceeds two
  /// standard errors over folds and outputs and play_bank_min_gain. Widths
  /// as in play_candidates. Empty: none.
  std::vector<std::vector<PlayChannel>> play_bank_candidates = {
      {PlayChannel(0.0), PlayChannel(0.07), PlayChannel(0.2)}};
  /// The least held-out gain (fit points, mean over outputs) that keeps a
  /// bank, beside the two standard errors: a bank triples the regressors of
  /// every later fit and the predictor's work, and on the real arm the
  /// folds' small gains (under a point) did not carry over to the held-out
  /// trial (docs/identification.md, "Banks of plays"). 0: two standard
  /// errors alone.
  double play_bank_min_gain = 1.0;
  /// Then the time constants (s) of a lag on the scheduling inputs
  /// (DioPwlObfModel::schedule_lag_s) tried against none, on the chosen
  /// model. Empty: no lag (the paper's schedule on the raw inputs).
  std::vector<double> schedule_lag_candidates = {0.1, 0.2, 0.4, 0.8};
  /// Then, on the chosen model, levels the play channels count from
  /// (InputShaping::threshold), as fractions of the largest training
  /// input level, tried against zero with the chosen and every growing play
  /// set; the kept coupling stays the same fraction of the top level above
  /// the threshold. A chamber that only stretches past an opening pressure.
  /// Empty: from zero.
  std::vector<double> play_threshold_candidates = {0.1, 0.2, 0.3};
  /// Softenings of the channels' level (InputShaping::softening), as
  /// fractions of the top level above the threshold (0.2: the top level is
  /// cut by 20%, less below it), tried with each threshold above, every
  /// growing set and none. Empty (default): linear levels. Input-side
  /// structures only (see play_refine_evaluations). Not chosen by default:
  /// docs/identification.md, 'Joint refinement'.
  std::vector<double> play_softening_candidates;
  /// Then, if > 0, at most this many held-out scores spent refining the
  /// chosen threshold, coupling, softening and the chosen channels' size
  /// together (NLopt BOBYQA, bounded, from the choice above): the stages
  /// above pick one setting at a time from coarse sets. Only the stages that
  /// ran (non-empty candidates; the size only with a channel) are refined.
  /// Kept only if the held-out k-step fit improves and the held-out
  /// simulation does not fall, so input-side structures only: the output side
  /// has no held-out simulation. 0 (default): no refinement.
  int play_refine_evaluations = 0;
  /// Then, for an input-side model, a sensor drift linear in time (a tip
  /// sensor's yaw, or each output's trend; output_drift.hpp), estimated and
  /// taken out of the training outputs. "off" (default): the outputs as
  /// logged; "auto": kept if held-out simulation against the logged outputs
  /// gains more than one standard error of that gain over folds and outputs;
  /// "on": always taken out. Taken out, the model carries the sensor's mean
  /// state over the training run. Off by default: one training run cannot
  /// tell a sensor's drift from a trend its physics leaves in that run, and
  /// on physics plsa did not write (whose sensor does not drift) "auto" kept
  /// a drift in 8 of 64 rows and cost them fits (docs/generalisation.md).
  OutputDriftChoice output_drift = OutputDriftChoice::kOff;
  /// Then, for an input-side model, the time constants (s) of one extra real
  /// pole in every bank, tried against none: dynamics slower than the local
  /// fits can see (creep, drift). Scored on simulation of the held-out
  /// blocks from the model's level, the horizon where a slow pole shows (it
  /// hardly moves a 40-step fit). Empty: no extra pole.
  std::vector<double> slow_pole_candidates = {2.0, 5.0, 10.0, 20.0};
  /// "tied" (default): the slow pole carries a fraction of each bank's own
  /// response through a first-order lag, one fraction for the model (tip
  /// frame: what creeps keeps the tip's direction) or one per output
  /// (slow_mode_tie.hpp); "free": its coefficients fitted freely per bank and
  /// output.
  SlowPoleForm slow_pole_form = SlowPoleForm::kTied;
  /// Tied: "level" (default) fits the fractions on the output increments,
  /// then steps them on the training runs' simulated level, keeping what
  /// simulates the training runs best (slow_fraction_levels.hpp);
  /// "increments": on the increments alone.
  SlowFractionFit slow_fraction_fit = SlowFractionFit::kLevel;
  /// At most this many slow poles (1 or 2): with one kept, each other
  /// candidate is tried beside it and the best is kept only if its held-out
  /// simulation gain over the one alone exceeds one standard error (creep
  /// spread over time scales, a Prony series, needs more than one).
  int slow_pole_count = 2;
  int play_selection_horizon = 40;  ///< samples ahead scored when choosing the play channels
  int play_selection_folds = 3;     ///< cross-validation folds
  /// How the folds cut the training logs. "interleaved": chunks of
  /// cv_chunk_s dealt to the folds in turn, so every fold's training part
  /// still spans the whole experiment; the regressors run over whole logs and
  /// a fold's chunks are weighted out of the fit (fitCoefficients' weights).
  /// "contiguous": each log in play_selection_folds time blocks, each block
  /// refitted from rest, so a held-out block is a stretch of the experiment
  /// (a part of the grid) that the fit has not seen.
  CvLayout cv_layout = CvLayout::kInterleaved;
  double cv_chunk_s = 8.0;
  /// The structure search scores its candidates on at most this many
  /// samples (search_sample.hpp): on longer logs, windows of about
  /// search_window_s spread evenly over them, each one's first 10 s fitted
  /// but not scored unless it starts its log (interleaved layout). The
  /// stages before the search and the final fit use every sample. About
  /// six and a half minutes at 80 Hz (four windows); 0: the search uses every sample.
  Eigen::Index search_max_samples = 32000;
  double search_window_s = 100.0;
  std::function<void(const std::string&)> progress;  ///< one line per stage
  /// Stage 5's held-out scores: after this long (s) without a line, one on
  /// how far the stage is (long logs, where a stage takes minutes). 0: after
  /// every score.
  double progress_interval_s = 5.0;
};

/// A pole candidate's held-out fits (IdentifyOptions::pole_method "auto",
/// or local windows' poles as a candidate): 40 steps ahead on the first
/// structure, and simulated on the first input-side structure (0 when no
/// structure schedules on the input side). `method`: "fkcm", "fcm", ...,
/// with "+windows" for the steps' and windows' poles together.
struct PoleMethodScore {
  std::string method;
  double step_ahead = 0.0, simulation = 0.0;
};

/// A quantile grid's level count scored as the play sets are: the held-out
/// fit 40 steps ahead (play_selection_horizon) of the first play set on the
/// input-side structure when one is offered, else on the structure
/// (scheduling) that scores best.
struct GridLevelScore {
  int levels = 0;
  double step_ahead = 0.0;
  std::string structure;  ///< the scored structure's tag as the progress lines print it: "N", "I" or "S"
};

struct PairPoles {
  int input = 0, output = 0;
  std::vector<std::complex<double>> identified;  ///< usable local poles
  /// Usable poles of local windows for an output whose steps gave fewer than
  /// a bank places: the second pole candidate's (with `identified`).
  std::vector<std::complex<double>> window_identified;
  /// Usable poles of the same windows fitted at second order, for an output
  /// without a usable step response when local_order is 1: the
  /// "+order2" pole candidates' (choosePoleMethod).
  std::vector<std::complex<double>> window_second_order;
  /// Poles of fits rejected only as badly determined or too weak for the
  /// noise (LocalFit::uncertain): used only when no output has a usable one.
  std::vector<std::complex<double>> uncertain;
  int rejected = 0;
  std::vector<std::string> rejections;  ///< why, one line each
  ClusteringResult chosen;
};

struct IdentifyReport {
  int segments = 0;
  /// The step references were the plateaus the measured inputs hold
  /// (plateauReference): no commands logged or named, and the inputs as
  /// logged gave no step.
  bool references_from_plateaus = false;
  /// The frame the outputs were fitted in and why (given, or chosen).
  OutputFrameChoice output_frame;
  std::vector<std::pair<std::vector<PlayChannel>, double>> play_scores;  ///< (candidate channels, held-out k-step fit)
  struct CouplingScore {
    std::vector<PlayChannel> set;
    double coupling;  ///< as given in the options
    double score;
  };
  std::vector<CouplingScore> coupling_scores;
  std::vector<CouplingScore> play_bank_scores;  ///< each bank of plays, uncoupled and with the chosen coupling
  /// The best bank's gain over the set chosen before it, and the gain's
  /// standard error over folds and outputs: kept when the gain is over
  /// twice that and over IdentifyOptions::play_bank_min_gain.
  std::pair<double, double> play_bank_gain{0.0, 0.0};
  std::vector<PlayChannel> play_bank_kept;  ///< the bank kept (its plays), empty when none was
  struct ThresholdScore {
    std::vector<PlayChannel> set;
    double threshold;  ///< as given in the options (0: none)
    double coupling;   ///< as given in the options, of the top level above the threshold
    double softening;  ///< as given in the options, of the top level above the threshold (0: none)
    double score;
  };
  std::vector<ThresholdScore> threshold_scores;
  /// The joint refinement (IdentifyOptions::play_refine_evaluations): its
  /// start and the best it found, as fractions like the options', and the
  /// channels' size as a factor of the chosen set's.
  struct PlayRefinement {
    double threshold = 0, coupling = 0, softening = 0, channel_scale = 1, score = 0;
  };
  PlayRefinement refine_start, refine_best;
  int refine_evaluations = 0;  ///< held-out scores spent (0: stage not run)
  /// Held-out simulation fit of the staged choice and of the refined point,
  /// scored when the refined point scored higher k steps ahead; it is kept
  /// only if the second is not lower. Both 0: not scored.
  std::pair<double, double> refine_simulation{0.0, 0.0};
  std::vector<std::pair<double, double>> schedule_lag_scores;  ///< (lag s, held-out k-step fit), 0 first
  std::vector<std::pair<double, double>>
      slow_pole_scores;  ///< (time constant s, held-out simulation fit), 0 (none) first
  /// The best slow pole's held-out simulation gain over none, mean and standard
  /// error over folds and outputs; it is kept only if the mean exceeds the error.
  std::pair<double, double> slow_pole_gain{0.0, 0.0};
  /// (time constant s, held-out simulation fit) of a second slow pole beside
  /// the first kept, the first alone (0) first; empty: not tried.
  std::vector<std::pair<double, double>> second_slow_pole_scores;
  /// The best second slow pole's gain over the first alone, as slow_pole_gain.
  std::pair<double, double> second_slow_pole_gain{0.0, 0.0};
  /// The kept slow poles' time constants (s); empty: none kept.
  std::vector<double> slow_pole_time_constants_s;
  /// Kept tied slow poles: the fraction of the response that creeps through
  /// each, [output](slow pole), in the final fit; empty otherwise.
  std::vector<Eigen::VectorXd> slow_pole_fraction;
  /// The kept slow poles' tie (no poles: none kept, or kept free): what a
  /// refit of the model's structure needs (the global linear baseline).
  SlowModeTie slow_pole_tie;
  std::pair<double, double> drift_scores{0.0, 0.0};  ///< held-out simulation fit: as logged, drift taken out
  /// Taking the drift out: held-out simulation gain over the outputs as
  /// logged, mean and standard error over folds and outputs; in "auto" it is
  /// taken out only if the mean exceeds the error. Both 0: not scored ("off",
  /// or an output-side model); (0, inf): fewer than two terms paired.
  std::pair<double, double> drift_gain{0.0, 0.0};
  /// Each pole candidate's held-out fits on the first play set: with
  /// pole_method "auto" FKcM's and fuzzy c-means', and, when some output has
  /// too few step poles (window_candidate_outputs), those with the windows'
  /// poles too if the steps' score below window_poles_below; empty when
  /// there was one candidate and no output short of step poles.
  std::vector<PoleMethodScore> pole_method_scores;
  /// Quantile grids (IdentifyOptions::quantile_levels 0 on logs without a
  /// staircase): each level count scored, from the automatic one up; empty
  /// when no finer count leaves its regions enough data, the levels were
  /// given or not to be scored (score_grid_levels), no input moves, or the
  /// logs hold a staircase.
  std::vector<GridLevelScore> grid_level_scores;
  int grid_levels = 0;           ///< a quantile grid's level count kept (0: the staircase's levels, or no input moves)
  OutputDrift output_drift;      ///< the drift estimated on the samples the search scored (empty rates: stage not run)
  bool drift_taken_out = false;  ///< whether the model was fitted to the outputs less output_drift
  Eigen::Index search_samples = 0;          ///< the samples the structure search scored on (search_max_samples)
  bool used_windows = false;                ///< some output's poles came from local windows (see window_outputs)
  std::vector<std::string> window_outputs;  ///< outputs without a usable step response, fitted on windows
  /// Outputs with fewer usable step poles than a bank places: local windows'
  /// poles with theirs were a second candidate (pole_method_scores, "+windows").
  std::vector<std::string> window_candidate_outputs;
  /// The logs hold a staircase: some output's poles came from its steps, so the
  /// partition follows the reference levels (if few) rather than quantiles.
  bool staircase = false;
  /// No local fit passed its checks: the poles came from PairPoles::uncertain.
  bool uncertain_poles = false;
  std::vector<PairPoles> pairs;
  CoefficientFitReport coefficients;
  std::vector<std::string> lines;  ///< everything the progress callback saw
};

/// Throws std::invalid_argument / std::runtime_error naming the log and the problem.
/// A candidate set as the progress lines print it: {0.10} fixed, {0.12u} growing.
std::string formatPlaySet(const std::vector<PlayChannel>& set);

DioPwlObfModel identifyModel(const std::vector<io::Log>& logs, const IdentifyOptions& options,
                             IdentifyReport* report = nullptr);

/// Partition helpers, exposed for tools and tests.
std::vector<double> midpoints(const std::vector<double>& levels);
std::vector<double> quantileBreakpoints(std::vector<double> values, int levels);

}  // namespace plsa::identify
