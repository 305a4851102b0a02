// `plsa validate` (model + log -> fits): k-step and simulation fits on one
// stated window, as a table, JSON and CSV.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/core/angle_units.hpp"
#include "plsa/core/number_text.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/eval/validation.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/model/model_file.hpp"

namespace plsa::app {
namespace {

struct ValidateArgs {
  std::string model;
  std::string log;
  std::vector<int> horizons{40, 80};
  std::string json;
  std::string csv;
  eval::SimulationStart start;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
  bool refuse_outliers = true;
};

// Seconds as the table prints them (printf's %g: 6 significant digits).
std::string seconds(double s) { return significantDigits(s, 6); }

// A fit in its column: two decimals, or significant digits past a million
// (a model whose simulation diverges scores -1e149, 150 characters wide).
std::string fitCell(double fit) {
  char b[32];
  std::snprintf(b, sizeof b, std::abs(fit) < 1e6 ? "%9.2f" : "%9.3g", fit);
  return b;
}

// The fits and rms errors as a table a person reads, and into `j`.
void printFits(FILE* table, const eval::ValidationResult& v, const std::vector<int>& horizons, nlohmann::json& j) {
  std::fprintf(table, "%-12s", "output");
  for (int k : horizons) std::fprintf(table, " %9s", ("k=" + std::to_string(k)).c_str());
  std::fprintf(table, " %9s\n", "sim");
  for (const auto& o : v.outputs) {
    std::fprintf(table, "%-12s", o.name.c_str());
    for (int k : horizons) {
      std::fprintf(table, " %s", fitCell(o.fit_k.at(k)).c_str());
      j["outputs"][o.name]["fit_k" + std::to_string(k)] = o.fit_k.at(k);
    }
    std::fprintf(table, " %s\n", fitCell(o.fit_sim).c_str());
    j["outputs"][o.name]["fit_sim"] = o.fit_sim;
  }
  // The same errors in the outputs' units, beside the spread the fit divides by.
  std::fprintf(table, "%-12s", "rms error");
  for (int k : horizons) std::fprintf(table, " %9s", ("k=" + std::to_string(k)).c_str());
  std::fprintf(table, " %9s %12s\n", "sim", "measured std");
  for (const auto& o : v.outputs) {
    std::fprintf(table, "%-12s", o.name.c_str());
    for (int k : horizons) {
      std::fprintf(table, " %9.4g", o.rms_k.at(k));
      j["outputs"][o.name]["rms_k" + std::to_string(k)] = o.rms_k.at(k);
    }
    std::fprintf(table, " %9.4g %12.4g\n", o.rms_sim, o.spread);
    j["outputs"][o.name]["rms_sim"] = o.rms_sim;
    j["outputs"][o.name]["std"] = o.spread;
  }
  // Why a k-step fit can fall below the simulation's: the error it restarts with.
  std::fprintf(table, "%-12s", "error kept");
  for (int k : horizons) std::fprintf(table, " %9s", ("k=" + std::to_string(k)).c_str());
  std::fprintf(table, "\n");
  for (const auto& o : v.outputs) {
    std::fprintf(table, "%-12s", o.name.c_str());
    for (int k : horizons) {
      std::fprintf(table, " %s", fitCell(o.sim_error_kept.at(k)).c_str());
      j["outputs"][o.name]["sim_error_kept_k" + std::to_string(k)] = o.sim_error_kept.at(k);
    }
    std::fprintf(table, "\n");
  }
  std::fprintf(table,
               "(error kept: the share of the simulation's error k samples back still there; a k-step prediction "
               "restarts from the measured output and carries that error, so below 0.5 its fit falls below the "
               "simulation's)\n");
  const Eigen::Index scored = v.time.size() - v.scored_from;
  std::fprintf(table, "(every column scored on the same %lld samples: %lld to the log's end, t = %s to %s s)\n",
               static_cast<long long>(scored), static_cast<long long>(v.scored_from),
               seconds(v.time(v.scored_from)).c_str(), seconds(v.time(v.time.size() - 1)).c_str());
  j["scored_samples"] = {{"first", v.scored_from},
                         {"count", scored},
                         {"first_time_s", v.time(v.scored_from)},
                         {"last_time_s", v.time(v.time.size() - 1)}};
}

// How the simulation started, in words (the ways differ when the log starts
// unsettled), into `j` with the yaw drift it carried and where it departed.
std::string describeSimulation(const DioPwlObfModel& model, const eval::SimulationStart& s,
                               const eval::ValidationResult& v,
                               const std::vector<eval::SimulationDeparture>& departures, nlohmann::json& j) {
  const std::string window = s.settle_s > 0
                                 ? seconds(s.yaw_registration_s) + " s after the first " + seconds(s.settle_s) + " s"
                                 : "first " + seconds(s.yaw_registration_s) + " s";
  const std::string kept = "model output level, training sensor yaw kept: the tip straight over the ";
  std::string start = model.output_level.empty() ? "first measured sample"
                      : !v.yaw_asked             ? "model output level"
                      : v.yaw.registered
                          ? "model output level, sensor yaw registered on the " + window + " (not scored)"
                          : kept + window + " (not scored)";
  if (v.yaw_asked)
    j["yaw_registration"] = {{"registered", v.yaw.registered},
                             {"offset_deg", v.yaw.offset / kRadPerDeg},
                             {"bent_share", v.yaw.bent_share},
                             {"min_bend_deg", s.yaw_registration_min_bend_deg},
                             {"tracking_s", s.yaw_tracking_s}};
  const double yaw_rate = eval::carriedYawRate(model, s);
  if (yaw_rate != 0.0)
    start += ", turning at the training run's sensor drift of " + significantDigits(yaw_rate, 4) + " " +
             model.output_unit + "/s";
  j["simulation_start"] = start;
  j["simulation_yaw_drift_deg_per_s"] = yaw_rate == 0.0 ? 0.0 : yaw_rate * model.radiansPerAngleUnit() / kRadPerDeg;
  j["simulation_departures"] = nlohmann::json::array();
  for (const eval::SimulationDeparture& d : departures)
    j["simulation_departures"].push_back({{"output", d.output},
                                          {"measured_low", d.measured_low},
                                          {"measured_high", d.measured_high},
                                          {"farthest", d.farthest},
                                          {"share_of_width", d.share},
                                          {"first_time_s", d.first_time_s}});
  return start;
}

void runValidate(const ValidateArgs& a) {
  for (const auto& [out, option] : {std::pair{a.json, "--json"}, std::pair{a.csv, "--csv"}}) {
    checkOutputPath(out, option, {a.model, a.log, a.can_profile}, "plsa validate");
  }
  if (a.csv != kStandardOutput) refuseOverwritingInputs(a.csv, "--csv", {a.json}, "plsa validate");
  if (a.json == kStandardOutput && a.csv == kStandardOutput)
    throw std::invalid_argument("plsa validate: --json and --csv cannot both be '-' (standard output)");
  // With an output on standard output, the table a person reads goes to standard error.
  FILE* table = a.json == kStandardOutput || a.csv == kStandardOutput ? stderr : stdout;
  const DioPwlObfModel model = loadModel(a.model);
  std::vector<std::string> required = model.inputs;
  required.insert(required.end(), model.outputs.begin(), model.outputs.end());
  required.push_back(io::standard_columns::kTime);  // the sample rate and gaps are checked against the model's
  const io::Log log = readLogs({a.log}, required, "validate", a.channel, a.can_profile).front();
  warnOfDeclaredUnits(log, model.input_unit, model.output_unit, "plsa validate");
  if (a.refuse_outliers) {
    const std::string outlier = identify::grossOutlier(log, {required.begin(), required.end() - 1});
    if (!outlier.empty())
      throw std::invalid_argument(outlier +
                                  ": a glitch would dominate the scores; remove the sample (or validate "
                                  "with --keep-outliers)");
  }
  const eval::ValidationResult v = validateModel(model, log, a.horizons, a.start);
  for (const std::string& w : eval::inputCoverageWarnings(model, v.outside_training))
    std::fprintf(stderr, "plsa validate: warning: %s\n", w.c_str());
  const std::vector<eval::SimulationDeparture> departures = eval::simulationDepartures(v);
  for (const std::string& w : eval::simulationWarnings(departures))
    std::fprintf(stderr, "plsa validate: warning: %s\n", w.c_str());
  for (const std::string& w : eval::unsettledStartWarnings(v.unsettled_starts))
    std::fprintf(stderr, "plsa validate: warning: %s\n", w.c_str());
  if (v.yaw_asked && !v.yaw.registered)
    std::fprintf(stderr,
                 "plsa validate: warning: the sensor's yaw was not registered: the tip was bent %s deg or more on "
                 "%.0f%% of the registration window (half is needed), so the simulation keeps the training run's "
                 "yaw; --settle SECONDS starts the window where the tip bends\n",
                 significantDigits(a.start.yaw_registration_min_bend_deg, 6).c_str(), 100.0 * v.yaw.bent_share);
  nlohmann::json j;
  printFits(table, v, a.horizons, j);
  j["model"] = a.model;
  j["log"] = a.log;
  j["metric"] = "NRMSE fit %, 100 (1 - ||y - yhat|| / ||y - mean y||)";
  j["rms_metric"] =
      "rms_*: sqrt(mean (y - yhat)^2) in the output's units; std: the measured output's standard "
      "deviation; every fit, rms and std over the same samples (scored_samples)";
  const std::string start = describeSimulation(model, a.start, v, departures, j);
  j["scored_samples"]["settle_s"] = a.start.settle_s;
  j["simulation_unsettled_starts"] = nlohmann::json::array();
  for (const eval::UnsettledStart& t : v.unsettled_starts)
    j["simulation_unsettled_starts"].push_back({{"output", t.output},
                                                {"later_s", t.later_s},
                                                {"rms_error", t.rms_error},
                                                {"rms_later", t.rms_later},
                                                {"straight_share", t.straight_share}});
  std::fprintf(table, "(sim from the %s)\n", start.c_str());
  if (!a.json.empty()) writeTextFile(a.json, j.dump(2) + "\n", "fits file");
  if (!a.csv.empty()) io::writeCsvLog(a.csv, eval::predictionLog(v));
}

// Accepts a duration in seconds >= 0; the error quotes the value and an example.
CLI::Validator durationValidator(const std::string& example) {
  return CLI::Validator(
      [example](std::string& v) {
        double x = NAN;
        return parseNonNegative(v, x) ? std::string()
                                      : "'" + v + "' is not a duration in seconds >= 0 (e.g. " + example + ")";
      },
      "SECONDS");
}

}  // namespace

void addValidateCommand(CLI::App& app) {
  auto v = std::make_shared<ValidateArgs>();
  CLI::App* va = app.add_subcommand("validate", "k-step-ahead and simulation NRMSE fits of a model on a log");
  va->add_option("--model", v->model, "Model file")->required()->check(CLI::ExistingFile);
  va->add_option("--log", v->log, "Validation log: CSV, or an LCM event log (known by its content, any name)")
      ->required()
      ->check(CLI::ExistingFile);
  va->add_option("--horizons", v->horizons, "Comma-separated horizons in samples")
      ->delimiter(',')
      ->check(CLI::Range(1, 1000000));
  va->add_option("--json", v->json, "Write fits as JSON ('-': standard output)")->check(kOutputPath);
  va->add_option("--csv", v->csv, "Write measured vs predicted as CSV ('-': standard output)")->check(kOutputPath);
  addLogFormatOptions(va, v->channel, v->can_profile);
  va->add_option("--yaw-registration", v->start.yaw_registration_s,
                 "tip_cartesian models with an output level: seconds at the log's start on which the sensor's yaw is "
                 "registered, as the predictor does (the simulation turned by it, the k-step predictions' increments "
                 "from the window's end on; every column is scored after it) (default 5); 0 carries the training "
                 "run's yaw")
      ->check(durationValidator("5, or 0 for none"));
  va->add_option("--yaw-min-bend", v->start.yaw_registration_min_bend_deg,
                 "the yaw registration reads only samples whose measured tip is bent at least this much (deg) and "
                 "keeps the training yaw unless they are half its window: a straight tip's direction is the "
                 "sensor's noise (default 1)")
      ->check(finiteNumberAtLeast(0.0, false));
  va->add_option("--yaw-tracking", v->start.yaw_tracking_s,
                 "tip_cartesian models with an output level: go on registering the sensor's yaw past the window, "
                 "each sample weighed down by e^-1 per this many seconds, and turn the k-step predictions by it (as "
                 "the predictor's yaw_tracking_s) instead of the window's offset and the training drift's "
                 "extrapolation; the simulation keeps the window's (default 60; 0: none)")
      ->check(finiteNumberAtLeast(0.0, false));
  va->add_option("--settle", v->start.settle_s,
                 "seconds at the log's start left out of every score, for a log that does not start at rest (the "
                 "simulation starts settled at the first sample's inputs; it and the predictions run through them) "
                 "(default 0)")
      ->check(durationValidator("10"));
  va->add_flag("!--no-drift", v->start.carry_training_drift,
               "tip_cartesian models with a training_output_drift: simulate without the sensor yaw drift the training "
               "run showed (by default the simulation turns at that rate over the log)");
  va->add_flag("!--keep-outliers", v->refuse_outliers,
               "Score samples that lie more than 50 times the width of their column's 1-99% band from its median "
               "(by default such a glitch is an error naming its row)");
  va->callback([v] { runValidate(*v); });
}

}  // namespace plsa::app
