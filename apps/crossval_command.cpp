// `plsa crossval`: leave-one-log-out validation of DIO-PWL-OBF against its
// peers fitted on the same logs (the paper's configuration, the global
// linear OBF and linear ARX), every model scored on the same samples: the
// project's real-data check.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <memory>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/eval/comparison.hpp"
#include "plsa/core/check.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/identify/baselines.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/io/standard_columns.hpp"

namespace fs = std::filesystem;

namespace plsa::app {
using namespace plsa::identify;  // this command drives identification
namespace {

struct CrossvalArgs {
  std::vector<std::string> logs;
  std::vector<std::string> inputs = io::standard_columns::pressures();
  std::vector<std::string> outputs = io::standard_columns::tipAngles();
  std::vector<int> horizons{1, 12};
  int arx_na = 4, arx_nb = 4;
  std::string json;
  IdentifyOptions options;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
};

// The models' keys in the JSON (MATLAB's jsondecode and pandas take them as
// they are) and the names printed ("labels" in the JSON), in the order fitted.
const char* const kKeys[] = {"plsa", "paper", "global_linear", "arx"};
const char* const kLabels[] = {"DIO-PWL-OBF", "paper's config", "global linear", "ARX"};
constexpr std::size_t kModelCount = std::size(kKeys);

using FitSums = std::vector<std::vector<std::map<int, double>>>;  // [model][output][horizon, 0: sim]

/// Folds are named by file stem; two files of one stem would share a row and
/// a JSON entry, so those keep their paths.
std::vector<std::string> foldNames(const std::vector<std::string>& files) {
  std::vector<std::string> names;
  for (const auto& f : files) names.push_back(fs::path(f).stem().string());
  for (std::size_t i = 0; i < files.size(); ++i)
    if (std::count(names.begin(), names.end(), names[i]) > 1) names[i] = files[i];
  return names;
}

/// Every fold trains on all logs but one: a log at another rate is named
/// here, against the rate most logs share, not in whichever fold meets it.
void requireOneSampleTime(const std::vector<io::Log>& logs, const std::vector<std::string>& files) {
  std::vector<double> dt;
  for (const auto& log : logs)
    dt.push_back(io::checkedSampleTime(log, io::standard_columns::kTime, io::kToleratedGapFactor));
  std::size_t common = 0, most = 0;
  for (std::size_t i = 0; i < dt.size(); ++i) {
    const auto n = static_cast<std::size_t>(
        std::count_if(dt.begin(), dt.end(), [&](double t) { return io::sameSampleTime(t, dt[i]); }));
    if (n > most) most = n, common = i;
  }
  for (std::size_t i = 0; i < dt.size(); ++i)
    if (!io::sameSampleTime(dt[i], dt[common]))
      throw std::invalid_argument("crossval: " + files[i] + ": sample time " + significantDigits(dt[i], 6) +
                                  " s differs from the " + significantDigits(dt[common], 6) + " s of " +
                                  std::to_string(most) + " of the " + std::to_string(dt.size()) +
                                  " logs; resample it or leave it out");
}

/// The logs, each long enough to score the longest horizon after ARX's lags
/// when held out.
std::vector<io::Log> readFoldLogs(const CrossvalArgs& a, const std::vector<std::string>& files) {
  io::CsvReadOptions ro;
  ro.required = a.inputs;
  ro.required.insert(ro.required.end(), a.outputs.begin(), a.outputs.end());
  ro.lcm_channel = a.channel;
  ro.can_profile = a.can_profile;
  std::vector<io::Log> logs;
  std::vector<std::string> read = files;
  read.push_back(a.can_profile);
  checkOutputPath(a.json, "--json", read, "plsa crossval");
  for (const auto& f : files) logs.push_back(readLogWithWarnings(f, ro, "crossval"));
  const int longest = *std::max_element(a.horizons.begin(), a.horizons.end());
  const int lags = std::max(a.arx_na, a.arx_nb);
  for (std::size_t i = 0; i < logs.size(); ++i)
    if (logs[i].samples() <= longest + lags)
      throw std::invalid_argument("crossval: " + files[i] + ": " + std::to_string(logs[i].samples()) +
                                  " samples are too few to score horizon " + std::to_string(longest) + " after ARX's " +
                                  std::to_string(lags) + " lags (a fit needs 2 samples); give a shorter horizon");
  // A copy under another name would be held out while itself trains (found by a probe).
  for (std::size_t i = 0; i < logs.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (logs[i].columns == logs[j].columns && logs[i].data.rows() == logs[j].data.rows() &&
          logs[i].data == logs[j].data)
        throw std::invalid_argument("crossval: " + files[i] + " holds the same samples as " + files[j] +
                                    "; a trial held out would train on its copy (remove one)");
  requireOneSampleTime(logs, files);
  return logs;
}

/// One fold: every model fitted on every log but `hold`, scored on it: plsa's;
/// the paper's configuration (identified with its own options: no drift taken
/// out, the outputs as logged); the global linear OBF (plsa's bases, one
/// region) and ARX, fitted to the outputs less any drift plsa's took out.
struct FoldResult {
  IdentifyReport report;
  std::vector<eval::ModelPredictions> predictions;
  std::vector<std::vector<std::map<int, eval::CommonScore>>> scores;
};

FoldResult scoreFold(const CrossvalArgs& a, const IdentifyOptions& o, const std::vector<io::Log>& logs,
                     std::size_t hold) {
  std::vector<io::Log> train;
  for (std::size_t r = 0; r < logs.size(); ++r)
    if (r != hold) train.push_back(logs[r]);
  FoldResult f;
  const DioPwlObfModel model = identifyModel(train, o, &f.report);
  const DioPwlObfModel paper = identifyModel(train, paperConfiguration(o));
  // The global linear OBF and ARX are fitted to the same outputs as the model: less any drift it took out.
  const BaselineData training = baselineData(model, f.report, train);
  const DioPwlObfModel linear = globalLinearOf(model, training);
  const eval::ArxModel arx = eval::ArxModel::fit(training.U, training.Y, a.arx_na, a.arx_nb);
  const Eigen::MatrixXd uv = logs[hold].columnsOf(a.inputs), yv = logs[hold].columnsOf(a.outputs);
  f.predictions = {
      eval::predictDio(kLabels[0], model, uv, yv, a.horizons), eval::predictDio(kLabels[1], paper, uv, yv, a.horizons),
      eval::predictDio(kLabels[2], linear, uv, yv, a.horizons), eval::predictArx(kLabels[3], arx, uv, yv, a.horizons)};
  f.scores = eval::commonScores(f.predictions, yv);
  return f;
}

/// The fold's rows (and its grid and drift lines), added to the sums and the JSON.
void printFold(const CrossvalArgs& a, const std::string& name, const FoldResult& f, FitSums& sums, nlohmann::json& j) {
  if (f.report.grid_levels > 0) {
    std::printf("%-12s quantile grid: %d levels per input%s\n", name.c_str(), f.report.grid_levels,
                f.report.grid_level_scores.empty() ? "" : " (chosen by held-out score)");
    j["folds"][name]["grid_levels"] = f.report.grid_levels;
  }
  if (!f.report.play_bank_scores.empty()) {
    const auto& [gain, se] = f.report.play_bank_gain;
    const bool kept = !f.report.play_bank_kept.empty();
    std::printf("%-12s bank of plays: %s (held-out gain %.3g +- %.2g)\n", name.c_str(),
                kept ? ("kept " + identify::formatPlaySet(f.report.play_bank_kept)).c_str() : "none kept", gain, se);
    j["folds"][name]["play_bank"] = {{"kept", kept}, {"gain", gain}, {"gain_se", se}};
  }
  if (f.report.drift_taken_out) {
    std::printf("%-12s sensor drift taken out of the training outputs (per s):", name.c_str());
    for (std::size_t out = 0; out < a.outputs.size(); ++out) {
      std::printf(" %s %.4g", a.outputs[out].c_str(), f.report.output_drift.rate[out]);
      j["folds"][name]["output_drift_per_s"][a.outputs[out]] = f.report.output_drift.rate[out];
    }
    std::printf("\n");
  }
  for (std::size_t m = 0; m < f.predictions.size(); ++m)
    for (std::size_t out = 0; out < a.outputs.size(); ++out) {
      std::printf("%-12s %-8s %-14s", name.c_str(), a.outputs[out].c_str(), f.predictions[m].name.c_str());
      auto& jf = j["folds"][name][kKeys[m]][a.outputs[out]];
      for (int k : a.horizons) {
        const eval::CommonScore& sc = f.scores[m][out].at(k);
        std::printf(" %8.1f", sc.fit);
        sums[m][out][k] += sc.fit;
        jf["fit_k" + std::to_string(k)] = sc.fit;
        jf["rms_k" + std::to_string(k)] = sc.rms;
      }
      const eval::CommonScore& sim = f.scores[m][out].at(0);
      std::printf(" %8.1f\n", sim.fit);
      sums[m][out][0] += sim.fit;
      jf["fit_sim"] = sim.fit;
      jf["rms_sim"] = sim.rms;
      jf["std"] = sim.spread;
    }
  std::fflush(stdout);
}

/// The mean rows over the folds, also into the JSON with the models' labels.
void printMeans(const CrossvalArgs& a, const FitSums& sums, std::size_t folds, nlohmann::json& j) {
  for (std::size_t m = 0; m < kModelCount; ++m) j["labels"][kKeys[m]] = kLabels[m];
  for (std::size_t m = 0; m < kModelCount; ++m)
    for (std::size_t out = 0; out < a.outputs.size(); ++out) {
      std::printf("%-12s %-8s %-14s", "mean", a.outputs[out].c_str(), kLabels[m]);
      for (int k : a.horizons) {
        const double v = sums[m][out].at(k) / static_cast<double>(folds);
        std::printf(" %8.1f", v);
        j["mean"][kKeys[m]][a.outputs[out]]["fit_k" + std::to_string(k)] = v;
      }
      const double v = sums[m][out].at(0) / static_cast<double>(folds);
      std::printf(" %8.1f\n", v);
      j["mean"][kKeys[m]][a.outputs[out]]["fit_sim"] = v;
    }
}

void runCrossval(CrossvalArgs& a) {
  std::vector<std::string> files = logPaths(a.logs, "crossval", true);
  std::sort(files.begin(), files.end());
  if (files.size() < 2) throw std::invalid_argument("crossval: need at least two logs (or a folder of them)");
  requireHorizons(a.horizons, "crossval");
  const std::vector<std::string> fold_names = foldNames(files);
  const std::vector<io::Log> logs = readFoldLogs(a, files);
  IdentifyOptions o = a.options;
  o.inputs = a.inputs;
  o.outputs = a.outputs;
  o.reference = a.inputs;  // measured data: segment on the inputs themselves
  std::printf("plsa crossval: %zu logs, leave one out; NRMSE fit %% (models scored on the same samples)\n",
              logs.size());
  std::printf("%-12s %-8s %-14s", "held out", "output", "model");
  for (int k : a.horizons) std::printf(" %8s", (std::to_string(k) + "-step").c_str());
  std::printf(" %8s\n", "sim");
  FitSums sums(kModelCount, std::vector<std::map<int, double>>(a.outputs.size()));
  nlohmann::json j;
  for (std::size_t hold = 0; hold < logs.size(); ++hold)
    printFold(a, fold_names[hold], scoreFold(a, o, logs, hold), sums, j);
  printMeans(a, sums, logs.size(), j);
  if (!a.json.empty()) writeTextFile(a.json, j.dump(2) + "\n", "fits file");
}

}  // namespace

void addCrossvalCommand(CLI::App& app) {
  auto a = std::make_shared<CrossvalArgs>();
  CLI::App* c = app.add_subcommand(
      "crossval", "Leave-one-log-out validation against the paper's configuration, global linear OBF and ARX");
  c->add_option("--log", a->logs, "Logs or folders of logs")->required();
  c->add_option("--inputs", a->inputs, "Input columns")->delimiter(',');
  c->add_option("--outputs", a->outputs, "Output columns")->delimiter(',');
  c->add_option("--horizons", a->horizons, "Horizons in samples")->delimiter(',')->check(CLI::Range(1, 1000000));
  c->add_option("--levels", a->options.quantile_levels,
                "Grid levels per input (quantiles); 0 (default): " + identify::IdentifyOptions::autoQuantileRule() +
                    " (plsa's model; the paper's configuration takes the count before refinement)")
      ->check(CLI::Range(0, 12));
  c->add_option("--local-order", a->options.local_order,
                "Order of plsa's local LTI fits, as in identify (default 1; the paper's configuration keeps 1)")
      ->check(CLI::Range(1, 6));
  addChoice(c, "--cv-layout", a->options.cv_layout,
            "Inner cross-validation of each training set: interleaved (default) or contiguous (see identify)");
  c->add_option("--play-softening", a->options.play_softening_candidates,
                "Candidate softenings of the play channels' level, as in identify; default none")
      ->delimiter(',')
      ->check(finiteNumber() & CLI::Range(0.0, 0.49));
  c->add_option("--refine-play", a->options.play_refine_evaluations,
                "Fits spent refining threshold, coupling, softening and band together, as in identify; default 0")
      ->check(CLI::Range(0, 10000));
  addPlayBankOptions(c, a->options);
  addChoice(c, "--output-drift", a->options.output_drift,
            "Sensor drift of plsa's model, as in identify: off (default), auto (estimated on each training set, "
            "kept when held-out simulation gains), on");
  c->add_option("--arx-na", a->arx_na, "ARX output lags")->check(CLI::Range(0, 64));
  c->add_option("--arx-nb", a->arx_nb, "ARX input lags")->check(CLI::Range(1, 64));
  c->add_option("--json", a->json, "Write the fits as JSON ('-': standard output)")->check(kOutputPath);
  addLogFormatOptions(c, a->channel, a->can_profile);
  c->callback([a] { runCrossval(*a); });
}

}  // namespace plsa::app
