// `plsa identify` (logs -> model file); `plsa validate` is in validate_command.cpp.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/identify/baselines.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::app {
using namespace plsa::identify;  // this command drives identification
namespace {

struct IdentifyArgs {
  std::vector<std::string> logs;
  std::vector<std::string> inputs = io::standard_columns::pressures();
  std::vector<std::string> outputs = io::standard_columns::tipAngles();
  std::vector<std::string> reference;
  std::string out;
  bool compare_poles = false;
  bool list_rejections = false;
  IdentifyOptions options;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
  std::string structure = "plsa";  ///< plsa, paper or global-linear
};

// What a rejection says without its numbers: "unstable pole 1.0011+0i" ->
// "unstable pole", "pole badly determined (std error 0.03)" -> "pole badly
// determined"; one key per "; "-separated reason after the location.
std::vector<std::string> rejectionKinds(const std::string& why) {
  const std::size_t colon = why.find(": ");
  std::istringstream reasons(colon == std::string::npos ? why : why.substr(colon + 2));
  std::vector<std::string> kinds;
  for (std::string reason; std::getline(reasons, reason, ';');) {
    std::istringstream words(reason);
    std::string kind;
    for (std::string w; words >> w;) {
      if (std::isdigit(static_cast<unsigned char>(w[0])) || w[0] == '-' || w[0] == '+' || w[0] == '(') break;
      kind += (kind.empty() ? "" : " ") + w;
    }
    if (!kind.empty()) kinds.push_back(kind);
  }
  return kinds;
}

// Each pair's rejected local fits: every one when few (or asked), otherwise
// a count by kind and the first, so an hour of data prints a line per pair,
// not hundreds.
void printRejections(const IdentifyReport& report, const std::vector<std::string>& inputs,
                     const std::vector<std::string>& outputs, bool list_all) {
  constexpr std::size_t kListed = 3;
  for (const auto& pp : report.pairs) {
    const std::string pair =
        inputs[static_cast<std::size_t>(pp.input)] + " -> " + outputs[static_cast<std::size_t>(pp.output)];
    if (list_all || pp.rejections.size() <= kListed) {
      for (const auto& why : pp.rejections)
        std::fprintf(stderr, "plsa identify:   rejected local fit %s, %s\n", pair.c_str(), why.c_str());
      continue;
    }
    std::vector<std::pair<std::string, int>> kinds;  // in order of first appearance
    for (const auto& why : pp.rejections)
      for (const auto& kind : rejectionKinds(why)) {
        auto at = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == kind; });
        if (at == kinds.end())
          kinds.emplace_back(kind, 1);
        else
          ++at->second;
      }
    std::string counts;
    std::size_t reasons = 0;
    for (const auto& [kind, n] : kinds) {
      counts += (counts.empty() ? "" : ", ") + std::to_string(n) + " " + kind;
      reasons += static_cast<std::size_t>(n);
    }
    if (reasons > pp.rejections.size()) counts += "; a fit can have several reasons";
    std::fprintf(
        stderr, "plsa identify:   rejected %zu local fits %s (%s); the first: %s (--list-rejections names every one)\n",
        pp.rejections.size(), pair.c_str(), counts.c_str(), pp.rejections.front().c_str());
  }
}

void runIdentify(IdentifyArgs& a) {
  IdentifyOptions o = a.options;
  o.inputs = a.inputs;
  o.outputs = a.outputs;
  o.reference = a.reference;
  o.progress = [](const std::string& line) { std::fprintf(stderr, "plsa identify: %s\n", line.c_str()); };
  std::vector<std::string> required = a.inputs;
  required.insert(required.end(), a.outputs.begin(), a.outputs.end());
  std::vector<std::string> read = a.logs;
  read.push_back(a.can_profile);
  checkOutputPath(a.out, "--out", read, "plsa identify");
  const auto logs = readLogs(a.logs, required, "identify", a.channel, a.can_profile);
  if (a.structure == "paper") {  // the peers the demo and generalise score plsa against
    const auto progress = o.progress;
    const int local_order = o.local_order;  // given with --structure paper, the user's choice
    o = paperConfiguration(o);
    o.progress = progress;
    o.local_order = local_order;
  }
  IdentifyReport report;
  DioPwlObfModel model = identifyModel(logs, o, &report);
  if (a.structure == "global-linear") {  // plsa's poles and play, one region, refitted on the logs
    const BaselineData b = baselineData(model, report, logs);
    model = globalLinearOf(model, b);
    o.progress(
        "global linear OBF: the poles and play channels chosen above, one region, no schedule lag, "
        "coefficients refitted on the logs");
  }
  printRejections(report, a.inputs, a.outputs, a.list_rejections);
  if (a.compare_poles) {
    // FKcM against fuzzy c-means, k-means and a global search on rho, same poles.
    std::printf("%-22s %6s %12s %12s %12s %12s %12s\n", "pair", "poles", "FKcM", "FKcM+rho", "fuzzy c-m", "k-means",
                "global");
    for (const auto& pp : report.pairs) {
      if (pp.identified.size() < 2) continue;
      ClusteringOptions co = o.clustering;
      co.centres = o.poles_per_pair;
      co.refine_on_rho = false;
      const double f = fkcmClustering(pp.identified, co).rho, c = fuzzyCMeansClustering(pp.identified, co).rho;
      co.refine_on_rho = true;
      const double fr = fkcmClustering(pp.identified, co).rho;
      const double k = kMeansClustering(pp.identified, co).rho, g = globalRhoSearch(pp.identified, co).rho;
      const std::string name =
          a.inputs[static_cast<std::size_t>(pp.input)] + " -> " + a.outputs[static_cast<std::size_t>(pp.output)];
      std::printf("%-22s %6zu %12.3e %12.3e %12.3e %12.3e %12.3e\n", name.c_str(), pp.identified.size(), f, fr, c, k,
                  g);
    }
  }
  saveModel(a.out, model);
  std::fprintf(stderr, "plsa identify: wrote %s\n", a.out.c_str());
}

// Accepts a time constant in seconds; the error quotes the value and an example.
CLI::Validator secondsValidator(const std::string& example) {
  return CLI::Validator(
      [example](std::string& v) {
        double x = NAN;
        // Above a day a pole is 1 to rounding at any sample time plsa reads.
        return parseNonNegative(v, x) && x <= 86400.0
                   ? std::string()
                   : "'" + v + "' is not a time constant in seconds up to a day (e.g. " + example + ")";
      },
      "SECONDS");
}

// identify's training logs and their columns.
void addTrainingLogOptions(CLI::App* id, const std::shared_ptr<IdentifyArgs>& a) {
  id->add_option("--log", a->logs,
                 "Training log(s): CSV, or LCM event logs (known by their content, any name); repeat for more")
      ->required()
      ->check(CLI::ExistingFile);
  addLogFormatOptions(id, a->channel, a->can_profile);
  id->add_option("--inputs", a->inputs, "Input columns (chamber pressures)")->delimiter(',');
  id->add_option("--outputs", a->outputs, "Output columns")->delimiter(',');
  id->add_option("--reference", a->reference, "Step reference columns (default cmd_* when present)")->delimiter(',');
}

// identify's local fits and pole clustering.
void addPoleOptions(CLI::App* id, const std::shared_ptr<IdentifyArgs>& a) {
  id->add_option("--poles", a->options.poles_per_pair, "OBF poles per input-output pair")->check(CLI::Range(1, 20));
  id->add_option("--local-order", a->options.local_order, "Order of the local LTI fits (paper: 1)")
      ->check(CLI::Range(1, 6));
  addChoice(id, "--pole-method", a->options.pole_method,
            "auto (default: FKcM and fuzzy c-means both, the one whose model scores higher on held-out data kept), "
            "fkcm (the paper's), fcm, kmeans or global");
  id->add_option("--rho-refinement", a->options.clustering.refine_on_rho,
                 "on (default): FKcM ends with a minimax on rho itself from its centres, kept where it lowers rho; "
                 "off: the paper's FKcM alone");
  id->add_option("--fuzziness", a->options.clustering.fuzziness, "FKcM fuzziness m > 1")
      ->check(finiteNumber() &
              CLI::Validator(
                  [](std::string& v) {
                    double m = NAN;
                    return parseNonNegative(v, m) && m >= 1.0 + 1e-9 && m <= 100.0
                               ? std::string()
                               : "'" + v + "' is not a fuzziness m over 1 (at least 1 + 1e-9) and at most 100 (e.g. 2)";
                  },
                  "M"));
  id->add_option("--window-poles-below", a->options.window_poles_below,
                 "An output with fewer usable step poles than --poles: local windows' poles are tried with its "
                 "steps' when the steps' model scores below this held-out fit % (default 0; 100: always)")
      ->check(finiteNumber(true));
  id->add_option("--second-order-windows-below", a->options.second_order_windows_below,
                 "An output without steps takes its poles from local windows: the windows' second-order poles are "
                 "tried too when the first-order poles' model scores below this held-out fit % (default 100: always; "
                 "-inf: never, as the paper)")
      ->check(finiteNumber(true));
  id->add_option("--levels", a->options.quantile_levels,
                 "Levels per input when the logs have no staircase (quantile grid); 0 (default): " +
                     identify::IdentifyOptions::autoQuantileRule())
      ->check(CLI::Range(0, 12));
  id->add_flag("--direction-split", a->options.direction_split, "Separate regions for rising and falling pressure");
}

// identify's output frame and scheduling.
void addFrameAndScheduling(CLI::App* id, const std::shared_ptr<IdentifyArgs>& a) {
  id->add_option_function<std::string>(
        "--output-frame",
        [a](const std::string& f) {
          if (f == "auto")
            a->options.output_frame.reset();
          else
            a->options.output_frame = outputFrameFromString(f);
        },
        "auto (default): tip_cartesian when the two outputs are named as a tip's bending and steering angles "
        "(e.g. bend_deg, steer_deg) and the bending is never negative, else as_logged; the choice is printed. "
        "tip_cartesian: the model runs on bend*cos(steer), bend*sin(steer), where a constant-curvature "
        "segment's dynamics are linear; predictions come back as the logged angles")
      ->check(CLI::IsMember({"auto", "as_logged", "tip_cartesian"}));
  id->add_option_function<std::string>(
        "--angle-unit",
        [a](const std::string& u) {
          if (u == "auto")
            a->options.angle_unit.reset();
          else
            a->options.angle_unit = u;
        },
        "The tip frame's bending and steering angles: deg or rad; auto (default): as the names say (deg, rad), "
        "else rad when every value lies within 2 pi and deg otherwise; the choice is printed")
      ->check(CLI::IsMember({"auto", "deg", "rad"}));
  addChoice(id, "--scheduling", a->options.scheduling,
            "auto (chosen by cross-validation), interpolated (coefficients blended between grid nodes), "
            "switched (the paper's PWL) or input (grid nodes weigh the inputs before the filters: no drift in "
            "simulation)");
}

// One candidate set of play channels, channels separated by '/', e.g. 0/0.1/0.12u.
std::vector<PlayChannel> parsePlaySet(const std::string& text, const std::string& option) {
  std::vector<PlayChannel> set;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, '/')) {
    const bool slope = !item.empty() && item.back() == 'u';
    const std::string number = slope ? item.substr(0, item.size() - 1) : item;
    double v = NAN;
    // A band wider than the input's whole range never moves: at most 1 (or 1u).
    if (!parseNonNegative(number, v) || v > 1.0)
      throw CLI::ValidationError(option,
                                 "'" + item + "' is not a width (e.g. 0.1) or a slope (e.g. 0.12u) of at most 1");
    set.push_back(slope ? PlayChannel(0.0, v) : PlayChannel(v));
  }
  return set;
}

// identify's candidates for the input shaping, the schedule's lag and the slow pole.
void addShapingCandidates(CLI::App* id, const std::shared_ptr<IdentifyArgs>& a) {
  id->add_option_function<std::vector<std::string>>(
        "--play",
        [a](const std::vector<std::string>& sets) {
          a->options.play_candidates.clear();
          for (const auto& s : sets) a->options.play_candidates.push_back(parsePlaySet(s, "--play"));
        },
        "Candidate play channel sets, comma-separated, channels within a set by '/': a width as a fraction of "
        "the input range (0.1) or a band growing with the level (0.12u: 12% of the pressure); "
        "e.g. 0,0.1,0.12u,0/0.1; '0' alone (and --play-bank none) is the paper's model")
      ->delimiter(',');
  addPlayBankOptions(id, a->options);
  id->add_option("--schedule-lag", a->options.schedule_lag_candidates,
                 "Candidate time constants (s) of a lag on the scheduling inputs, tried against none by "
                 "cross-validation; '0' alone keeps the paper's schedule on the raw inputs")
      ->delimiter(',')
      ->check(secondsValidator("0.4"));
  id->add_option("--play-coupling", a->options.play_coupling_candidates,
                 "Candidate couplings of each play channel to the other inputs, as fractions of the largest training "
                 "input (0.3: a full neighbour cuts a chamber's level by 30%), tried by cross-validation; '0' alone "
                 "couples none")
      ->delimiter(',')
      ->check(finiteNumber() & CLI::Range(0.0, 0.95));
  id->add_option("--play-threshold", a->options.play_threshold_candidates,
                 "Candidate levels the play channels count from, as fractions of the largest training input (a "
                 "chamber's opening pressure), tried against zero by cross-validation; '0' alone counts from zero")
      ->delimiter(',')
      ->check(finiteNumber() & CLI::Range(0.0, 0.95));
  id->add_option("--play-softening", a->options.play_softening_candidates,
                 "Candidate softenings of the play channels' level, x - s x^2 above the threshold, as fractions of "
                 "the top level above it (0.2: the top level cut by 20%), tried against none with each threshold; "
                 "input-side structures only; default none")
      ->delimiter(',')
      ->check(finiteNumber() & CLI::Range(0.0, 0.49));
  id->add_option("--refine-play", a->options.play_refine_evaluations,
                 "At most this many cross-validated fits spent refining the chosen threshold, coupling, softening "
                 "and play channel size together (NLopt BOBYQA from the choice; the stages that ran); kept if the "
                 "held-out fit improves and held-out simulation does not fall; input-side structures only; "
                 "default 0 (none)")
      ->check(CLI::Range(0, 10000));
  id->add_option(
        "--slow-pole", a->options.slow_pole_candidates,
        "Candidate time constants (s) of one extra real pole in every bank of an input-side model, for "
        "creep and drift, tried against none by cross-validated simulation and kept only if the best gains more "
        "than one standard error over folds and outputs, or more than two on one output, losing on none; '0' "
        "alone adds none")
      ->delimiter(',')
      ->check(secondsValidator("5"));
  addChoice(id, "--slow-pole-form", a->options.slow_pole_form,
            "tied (default): the slow pole carries a fitted fraction of each bank's own response through a "
            "first-order lag, one fraction for the model with tip_cartesian (what creeps keeps the tip's "
            "direction), one per output otherwise; free: its coefficients fitted freely per bank and output");
  addChoice(id, "--slow-fraction-fit", a->options.slow_fraction_fit,
            "level (default): the tied fractions fitted on the output increments, then stepped on the training "
            "runs' simulated level, keeping what simulates them best; increments: on the increments alone");
  id->add_option("--slow-pole-count", a->options.slow_pole_count,
                 "At most this many slow poles: with one kept, each other --slow-pole candidate is tried beside "
                 "it and the best kept by the same rule against the one alone; default 2")
      ->check(CLI::Range(1, 2));
}

// identify's output drift, cross-validation layout and outlier check.
void addDriftAndValidationOptions(CLI::App* id, const std::shared_ptr<IdentifyArgs>& a) {
  addChoice(id, "--output-drift", a->options.output_drift,
            "off (default): fit the outputs as logged; auto: estimate a sensor drift linear in time (a tip "
            "sensor's yaw with tip_cartesian, each output's trend otherwise) on an input-side model and take it "
            "out of the training outputs if cross-validated simulation gains more than one standard error over "
            "folds and outputs (for a sensor known to drift, as the built-in simulator's yaw does); on: always "
            "take it out");
  addChoice(id, "--cv-layout", a->options.cv_layout,
            "How cross-validation cuts the training logs for every choice above: interleaved (default): chunks "
            "of --cv-chunk seconds dealt to the folds in turn, so each fold's fit spans the whole experiment; "
            "contiguous: each log in three time blocks, each scored by a fit on the other two");
  id->add_option("--cv-chunk", a->options.cv_chunk_s, "Seconds per interleaved cross-validation chunk (default 8)")
      ->check(kPositive);
  id->add_option("--search-samples", a->options.search_max_samples,
                 "Score the structure search's candidates on at most this many samples: on longer logs, windows of "
                 "about 100 s spread evenly over them; the local fits, poles, partition and the final fit still use "
                 "every sample (default 32000, 6.7 min at 80 Hz; 0: search on every sample)")
      ->check(kNonNegative);
  id->add_flag("!--keep-outliers", a->options.refuse_outliers,
               "Fit samples that lie more than 50 times the width of their column's 1-99% band from its median "
               "(by default such a glitch is an error naming its row)");
}

void addIdentifyCommand(CLI::App& app) {
  auto a = std::make_shared<IdentifyArgs>();
  CLI::App* id = app.add_subcommand("identify", "Identify a DIO-PWL-OBF model from logs (paper Table I)");
  addTrainingLogOptions(id, a);
  addPoleOptions(id, a);
  addFrameAndScheduling(id, a);
  addShapingCandidates(id, a);
  addDriftAndValidationOptions(id, a);
  id->add_flag("--compare-poles", a->compare_poles, "Print rho of FKcM, fuzzy c-means, k-means and a global search");
  id->add_flag("--list-rejections", a->list_rejections,
               "Name every rejected local fit (default: each pair's first and a count by reason when over 3)");
  id->add_option("--structure", a->structure,
                 "plsa (the method with its extensions), paper (the paper's configuration: switched PWL, no play, "
                 "outputs as logged) or global-linear (plsa's poles and play, one region: the linear baseline)")
      ->check(CLI::IsMember({"plsa", "paper", "global-linear"}))
      ->capture_default_str();
  id->add_option("--out", a->out, "Model file (JSON)")->required()->check(kOutputPath);
  id->callback([a] { runIdentify(*a); });
}

}  // namespace

// identify's and crossval's banks of plays and the least gain that keeps one.
void addPlayBankOptions(CLI::App* app, identify::IdentifyOptions& options) {
  app->add_option_function<std::vector<std::string>>(
         "--play-bank",
         [&options](const std::vector<std::string>& banks) {
           options.play_bank_candidates.clear();
           for (const auto& s : banks) {
             if (s == "none") continue;
             options.play_bank_candidates.push_back(parsePlaySet(s, "--play-bank"));
             if (options.play_bank_candidates.back().size() < 2)
               throw CLI::ValidationError("--play-bank",
                                          "'" + s + "' is one play; a bank has two or more (0/0.07/0.2)");
           }
         },
         "Candidate banks of plays (a Prandtl-Ishlinskii operator: several widths per input, each weighted by the "
         "least squares; 0 is its linear part), comma-separated, plays within a bank by '/' as in --play; each "
         "tried on the chosen scheduling, uncoupled and with the chosen coupling, against the chosen play set; "
         "'none' tries none (default 0/0.07/0.2)")
      ->delimiter(',');
  app->add_option("--play-bank-min-gain", options.play_bank_min_gain,
                  "The least held-out gain (fit points) that keeps a bank of plays, beside two standard errors "
                  "(default 1; 0: two standard errors alone)")
      ->check(kNonNegative);
}

void addIdentifyCommands(CLI::App& app) {
  addIdentifyCommand(app);
  addValidateCommand(app);
}

}  // namespace plsa::app
