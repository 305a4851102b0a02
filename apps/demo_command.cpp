// `plsa demo`: the README's main job, on the built-in simulated actuator with
// every effect on: the paper's protocol (two-chamber grid identification,
// joystick validation), against the paper's switched PWL and two baselines,
// with the model, fits and a self-contained HTML report written to --out.
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "plsa/core/number_text.hpp"
#include "log_paths.hpp"
#include "plsa/eval/comparison.hpp"
#include "plsa/identify/baselines.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/report/svg_chart.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/io/standard_columns.hpp"

namespace fs = std::filesystem;

namespace plsa::app {
using namespace plsa::identify;  // this command drives identification
namespace {

struct DemoOptions {
  std::string out_dir = "plsa-demo";
  std::string config;
  std::uint64_t seed = 1;
};

std::string fmt(double v, const char* f = "%.1f") {
  char b[32];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

// The demo's output folder: the path of each file, refused when it is an input.
struct OutputFolder {
  std::string dir;
  std::string operator()(const std::string& f) const { return (fs::path(dir) / f).string(); }
};

// 1. Experiments (paper Table I, step 3; validation run as in its Section VI).
struct DemoRuns {
  io::Log train, val;
};

DemoRuns recordRuns(const sim::SimConfig& config, std::uint64_t seed, const OutputFolder& path) {
  sim::ExperimentOptions eo;
  eo.sample_rate_hz = config.sample_rate_hz;
  eo.seed = seed + 1;
  sim::Actuator rig_id(config, seed);
  DemoRuns r{sim::runExperiment(rig_id, sim::gridExperiment(eo)), {}};
  sim::Actuator rig_val(config, seed + 100);
  r.val = sim::runExperiment(rig_val, sim::joystickExperiment(eo));
  io::writeCsvLog(path("train_grid2.csv"), r.train);
  io::writeCsvLog(path("validate_joystick.csv"), r.val);
  std::printf("  experiments: two-chamber grid 0.20-0.35 bar (%lld samples), joystick validation (%lld samples)\n",
              static_cast<long long>(r.train.samples()), static_cast<long long>(r.val.samples()));
  return r;
}

// 2. Identification: plsa's (tip frame, input side; play, coupling, lag,
// threshold, slow pole and, where the simulated sensor drifts, its drift by
// cross-validation), the paper's (switched, no play, the angles as logged)
// and the two linear baselines.
struct DemoModels {
  bool drift_asked = false;  ///< whether plsa's identification ran the drift stage
  IdentifyReport report;
  DioPwlObfModel model, paper, linear;
  eval::ArxModel arx;
};

// Whether the simulated sensor drifts: then the demo asks identification
// for the drift stage (--output-drift auto), as a user whose sensor is known
// to drift would; identify's default leaves the outputs as logged.
bool sensorDrifts(const sim::SimConfig& config) {
  const auto& b = config.sensor_bias;
  return config.effectEnabled("sensor_bias") &&
         (b.yaw_drift_deg_per_s != 0.0 || b.drift_x_deg_per_s != 0.0 || b.drift_y_deg_per_s != 0.0);
}

DemoModels identifyModels(const io::Log& train, bool drifting_sensor, const OutputFolder& path) {
  IdentifyOptions io_;
  // The output frame is identification's own choice: bend_deg and steer_deg
  // are read as the tip direction's polar coordinates (output_frame_choice.hpp).
  // The grid moves one input at a time, so its held-out blocks cannot show the
  // drift of output-side gains along a wandering path; input side has none
  // (docs/identification.md).
  io_.scheduling = SchedulingChoice::kInputSide;
  if (drifting_sensor) io_.output_drift = OutputDriftChoice::kAuto;
  io_.progress = [](const std::string& l) { std::printf("  identify: %s\n", l.c_str()); };
  DemoModels m;
  m.drift_asked = drifting_sensor;
  m.model = identifyModel({train}, io_, &m.report);
  m.paper = identifyModel({train}, paperConfiguration(io_));
  // The baselines are fitted to the same outputs as plsa's model: less any sensor drift it took out.
  const BaselineData training = baselineData(m.model, m.report, {train});
  m.linear = globalLinearOf(m.model, training);
  m.arx = eval::ArxModel::fit(training.U, training.Y, 4, 4);
  saveModel(path("model.json"), m.model);
  // The baselines that are DIO models too, so that `plsa validate` can re-score them.
  saveModel(path("baseline_paper.json"), m.paper);
  saveModel(path("baseline_global_linear.json"), m.linear);
  return m;
}

// 3. Validation on the joystick run: every model, horizon and simulation
// start scored over the same samples.
struct DemoScores {
  std::vector<eval::ModelPredictions> preds;  ///< the four models, simulations as validate starts them
  std::vector<std::vector<std::map<int, eval::CommonScore>>> all;  ///< preds, then the two other starts
  Eigen::Index scored_from = 0;
  Eigen::VectorXd t;  ///< the run's time from its start
  std::string window, reg_s;
  double fit(std::size_t start, std::size_t m, std::size_t o, int key) const {
    return all[start * preds.size() + m][o].at(key).fit;
  }
  const std::map<int, eval::CommonScore>& at(std::size_t m, std::size_t o) const { return all[m][o]; }
};

DemoScores scoreOnJoystick(const DemoModels& m, const io::Log& val) {
  const std::vector<int> horizons = {40, 80};
  const Eigen::MatrixXd Uv = val.columnsOf(m.model.inputs), Yv = val.columnsOf(m.model.outputs);
  const eval::InputsOutsideTraining coverage = eval::inputsOutsideTraining(m.model, Uv);
  std::printf(
      "  the joystick run has an input outside its training range on %.1f%% of its samples and beyond the "
      "training grid's outer nodes on %.1f%%\n",
      100 * coverage.any, 100 * coverage.any_beyond_grid);
  for (const std::string& w : eval::inputCoverageWarnings(m.model, coverage)) std::printf("    %s\n", w.c_str());
  // ARX was fitted to the same drift-free outputs: its simulation gets the same drift back.
  const std::vector<double> arx_drift = m.report.drift_taken_out ? m.report.output_drift.rate : std::vector<double>{};
  DemoScores s;
  s.preds = {eval::predictDio("DIO-PWL-OBF (plsa)", m.model, Uv, Yv, horizons),
             eval::predictDio("DIO-PWL-OBF as in the paper", m.paper, Uv, Yv, horizons),
             eval::predictDio("global linear OBF (same poles, play)", m.linear, Uv, Yv, horizons),
             eval::predictArx("linear ARX(4,4)", m.arx, Uv, Yv, horizons, arx_drift, m.model.sample_time_s)};
  // The simulations again without the training drift; then, for the
  // tip-frame models, carrying the grid run's sensor yaw instead of
  // registering the joystick run's on its first 5 s, with no drift either.
  // The paper's model starts from the measured sample either way. All scored
  // on one window: after the registration.
  const eval::SimulationStart no_drift{eval::SimulationStart{}.yaw_registration_s, false}, training_yaw{0, false};
  s.reg_s = fmt(eval::SimulationStart{}.yaw_registration_s, "%g");
  std::vector<eval::ModelPredictions> all = s.preds;
  for (const eval::SimulationStart& st : {no_drift, training_yaw}) {
    all.push_back(predictDio("", m.model, Uv, Yv, horizons, st));
    all.push_back(s.preds[1]);
    all.push_back(predictDio("", m.linear, Uv, Yv, horizons, st));
    all.push_back(predictArx("", m.arx, Uv, Yv, horizons));
  }
  s.all = eval::commonScores(all, Yv);
  s.scored_from = eval::commonScoringStart(all);
  s.t = val.column(io::standard_columns::kTime).array() - val.column(io::standard_columns::kTime)(0);
  s.window = "samples " + std::to_string(s.scored_from) + " to " + std::to_string(Yv.rows() - 1) +
             ", t = " + fmt(s.t(s.scored_from), "%g") + " to " + fmt(s.t(s.t.size() - 1), "%g") + " s";
  return s;
}

// The fits table on standard output and in fits.json.
void writeFits(const DemoModels& m, const DemoScores& s, const OutputFolder& path) {
  const std::vector<std::string>& outputs = m.model.outputs;
  std::printf("\n  NRMSE fit %% on the joystick run (100 = perfect; every model, horizon and error on the same %s)\n",
              s.window.c_str());
  std::printf(
      "  sim: the tip-frame models register the run's sensor yaw on its first %s s, as the others start\n"
      "  from its first sample, and the models fitted without the grid run's sensor drift turn at its rate;\n"
      "  their 40- and 80-step predictions turn with it (as plsa's predictor does);\n"
      "  no drift: the simulation does not; training yaw: it carries the grid run's yaw, no drift\n",
      s.reg_s.c_str());
  std::printf("  %-36s %-10s %8s %8s %8s %9s %13s\n", "model", "output", "40-step", "80-step", "sim", "no drift",
              "training yaw");
  nlohmann::json j;
  // Keyed by a machine key (MATLAB's jsondecode and pandas take it as is);
  // the name people read is the entry's "label".
  const std::array<const char*, 4> keys = {"plsa", "paper", "global_linear", "arx"};
  const std::array<const char*, 4> files = {"model.json", "baseline_paper.json", "baseline_global_linear.json", ""};
  for (std::size_t k = 0; k < s.preds.size(); ++k) {
    j["models"][keys[k]]["label"] = s.preds[k].name;
    if (*files[k]) j["models"][keys[k]]["file"] = files[k];
  }
  for (std::size_t k = 0; k < s.preds.size(); ++k)
    for (std::size_t o = 0; o < outputs.size(); ++o) {
      const auto& f = s.at(k, o);
      const double f_nd = s.fit(1, k, o, 0), f_ty = s.fit(2, k, o, 0);
      std::printf("  %-36s %-10s %8.1f %8.1f %8.1f %9.1f %13.1f\n", s.preds[k].name.c_str(), outputs[o].c_str(),
                  f.at(40).fit, f.at(80).fit, f.at(0).fit, f_nd, f_ty);
      j["models"][keys[k]][outputs[o]] = {{"fit_k40", f.at(40).fit},      {"fit_k80", f.at(80).fit},
                                          {"fit_sim", f.at(0).fit},       {"fit_sim_no_drift", f_nd},
                                          {"fit_sim_training_yaw", f_ty}, {"rms_k40", f.at(40).rms},
                                          {"rms_k80", f.at(80).rms},      {"rms_sim", f.at(0).rms}};
    }
  // A fit divides by the run's spread, and a run that hardly bends makes a
  // small error a large miss: say both.
  std::printf("  plsa's errors in degrees (rms; 40-step / 80-step / sim) against the measured spread (std):\n");
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    const auto& f = s.at(0, o);
    std::printf("    %-10s %.3f / %.3f / %.3f deg rms, spread %.2f deg\n", outputs[o].c_str(), f.at(40).rms,
                f.at(80).rms, f.at(0).rms, f.at(0).spread);
    j["outputs"][outputs[o]] = {{"fit_k40", f.at(40).fit},
                                {"fit_k80", f.at(80).fit},
                                {"fit_sim", f.at(0).fit},
                                {"fit_sim_no_drift", s.fit(1, 0, o, 0)},
                                {"fit_sim_training_yaw", s.fit(2, 0, o, 0)},
                                {"rms_k40", f.at(40).rms},
                                {"rms_k80", f.at(80).rms},
                                {"rms_sim", f.at(0).rms},
                                {"std", f.at(0).spread}};
  }
  j["metric"] = "NRMSE fit %, 100 (1 - ||y - yhat|| / ||y - mean y||)";
  j["rms_metric"] =
      "rms_*: sqrt(mean (y - yhat)^2) in degrees; std: the measured output's standard deviation; "
      "every fit, rms and std over the same samples (scored_samples)";
  j["scored_samples"] = {{"first", s.scored_from},
                         {"count", s.t.size() - s.scored_from},
                         {"first_time_s", s.t(s.scored_from)},
                         {"last_time_s", s.t(s.t.size() - 1)}};
  writeTextFile(path("fits.json"), j.dump(2) + "\n", "fits file");
}

// The report's fit and error tables.
void reportTables(std::ostringstream& html, const DemoModels& m, const DemoScores& s) {
  html << "<h2>Fits (NRMSE %)</h2><p>Every model, horizon and error is scored on the same " << s.window
       << " into the run. sim: the tip-frame models (plsa's and the global linear OBF) register the joystick run's "
       << "sensor yaw on its first " << s.reg_s << " s, as the other two start from its first sample; the models "
       << "fitted without the grid run's sensor drift turn at its rate; their 40- and 80-step predictions turn with "
       << "it, as plsa's predictor does. sim, no drift: they do not. sim, training "
       << "yaw: the tip-frame models carry the grid run's yaw instead, with no drift.</p><table><tr><th>model</th>"
       << "<th>output</th><th>40-step</th><th>80-step</th><th>sim</th><th>sim, no drift</th><th>sim, training yaw</th>"
       << "</tr>";
  for (std::size_t k = 0; k < s.preds.size(); ++k)
    for (std::size_t o = 0; o < m.model.outputs.size(); ++o)
      html << "<tr><td>" << report::escape(s.preds[k].name) << "</td><td>" << m.model.outputs[o] << "</td><td>"
           << fmt(s.at(k, o).at(40).fit) << "</td><td>" << fmt(s.at(k, o).at(80).fit) << "</td><td>"
           << fmt(s.at(k, o).at(0).fit) << "</td><td>" << fmt(s.fit(1, k, o, 0)) << "</td><td>"
           << fmt(s.fit(2, k, o, 0)) << "</td></tr>";
  html << "</table><p>The same errors in degrees (rms), against the spread each fit divides by:</p><table><tr>"
       << "<th>model</th><th>output</th><th>40-step</th><th>80-step</th><th>sim</th><th>measured std</th></tr>";
  for (std::size_t k = 0; k < s.preds.size(); ++k)
    for (std::size_t o = 0; o < m.model.outputs.size(); ++o)
      html << "<tr><td>" << report::escape(s.preds[k].name) << "</td><td>" << m.model.outputs[o] << "</td><td>"
           << fmt(s.at(k, o).at(40).rms, "%.3f") << "</td><td>" << fmt(s.at(k, o).at(80).rms, "%.3f") << "</td><td>"
           << fmt(s.at(k, o).at(0).rms, "%.3f") << "</td><td>" << fmt(s.at(k, o).at(0).spread, "%.2f") << "</td></tr>";
  html << "</table>";
}

// The pole map: identified local poles, FKcM centres and the cross-validated slow pole.
std::string demoPoleMap(const DemoModels& m) {
  std::vector<report::PoleGroup> groups;
  std::vector<std::complex<double>> identified, centres, slow;
  for (const auto& pp : m.report.pairs) {
    identified.insert(identified.end(), pp.identified.begin(), pp.identified.end());
    centres.insert(centres.end(), pp.chosen.centres.begin(), pp.chosen.centres.end());
    // Poles the model carries beyond the FKcM centres: the cross-validated slow pole.
    const auto used = m.model.poles[static_cast<std::size_t>(pp.output)][static_cast<std::size_t>(pp.input)].poles();
    if (used.size() > pp.chosen.centres.size()) slow.push_back(used.back());
  }
  double zoom = 1.0;
  for (const auto& p : identified) zoom = std::min(zoom, p.real());
  for (const auto& p : centres) zoom = std::min(zoom, p.real());
  groups.push_back({"identified local poles", identified, "#1f77b4", false});
  groups.push_back({"FKcM centres (OBF poles)", centres, "#d62728", true});
  if (!slow.empty()) groups.push_back({"slow pole (cross-validated)", slow, "#2ca02c", true});
  return report::poleMap("Pole map: identified poles, FKcM centres and the slow pole", groups,
                         std::max(-1.0, zoom - 0.05));
}

// 4. The self-contained HTML report.
// What the report plots, as a CSV log beside it: the run's time and, per
// output, the measured value and plsa's 40-step, 80-step and simulated
// predictions (nan where a horizon has none yet, as validate --csv writes).
void writePredictionsCsv(const DemoModels& m, const DemoScores& s, const Eigen::MatrixXd& Yv, const std::string& file) {
  io::Log log;
  log.source = file;
  log.comments = {"plsa demo: the validation run and plsa's predictions of it, as report.html plots them"};
  log.columns = {"time_s"};
  std::vector<Eigen::VectorXd> columns{s.t};
  for (std::size_t o = 0; o < m.model.outputs.size(); ++o) {
    const auto& p = s.preds[0].by_output[o];
    const std::string& name = m.model.outputs[o];
    for (const auto& [suffix, v] : {std::pair<std::string, Eigen::VectorXd>{"", Yv.col(static_cast<Eigen::Index>(o))},
                                    {"_k40", p.at(40)},
                                    {"_k80", p.at(80)},
                                    {"_sim", p.at(0)}}) {
      log.columns.push_back(name + suffix);
      columns.push_back(v);
    }
  }
  log.data.resize(s.t.size(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) log.data.col(static_cast<Eigen::Index>(c)) = columns[c];
  io::writeCsvLog(file, log);
}

void writeReport(const DemoModels& m, const DemoScores& s, const io::Log& val, const std::string& effects,
                 const OutputFolder& path) {
  const std::string drift_text =
      m.report.drift_taken_out
          ? "A sensor yaw drift of " + significantDigits(m.report.output_drift.rate[1], 3) +
                " deg/s was found in the grid run and taken out of the training outputs of plsa's model and of the "
                "linear baselines; their simulations (sim) turn at that rate over the validation run, as its sensor "
                "drifts on (sim, no drift: they do not). "
          : std::string();
  const Eigen::MatrixXd Yv = val.columnsOf(m.model.outputs);
  std::ostringstream html;
  html << "<!doctype html><html><head><meta charset=\"utf-8\"><title>plsa demo</title><style>"
       << "body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}table{border-collapse:collapse}"
       << "td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}td:first-child,th:first-child{text-align:left}"
       << "pre{white-space:pre-wrap;font-size:12px}"
       << "</style></head><body><h1>plsa demo: DIO-PWL-OBF on the simulated actuator</h1>"
       << "<p>Identified on a two-chamber grid experiment (0.20 to 0.35 bar, four levels per chamber, one input moving "
          "at a "
       << "time), validated on a joystick-like run. Effects on: " << report::escape(effects) << ". plsa's model runs "
       << "on the tip direction's components (bend cos steer, bend sin steer) with input-side scheduling; play, "
       << "coupling, schedule lag, play threshold, slow pole"
       << (m.drift_asked ? " and (the simulated sensor drifting) sensor drift" : "")
       << " chosen by cross-validation on the grid. " << drift_text
       << "Every model is scored on the logged angles.</p>";
  reportTables(html, m, s);
  html << "<p>Every plotted series: <a href=\"predictions.csv\">predictions.csv</a>. " << report::kChartHint << "</p>";
  for (std::size_t o = 0; o < m.model.outputs.size(); ++o) {
    const auto& p = s.preds[0].by_output[o];
    const Eigen::VectorXd y = Yv.col(static_cast<Eigen::Index>(o));
    const std::string& name = m.model.outputs[o];
    html << report::lineChart(name + ": measured vs predicted (DIO-PWL-OBF, plsa)", s.t,
                              {{"measured", y, "#222", false},
                               {"40-step", p.at(40), "#1f77b4", false},
                               {"80-step", p.at(80), "#2ca02c", true},
                               {"simulation", p.at(0), "#d62728", false}},
                              "time (s)", name);
    html << report::lineChart(
        name + ": residual, measured minus predicted", s.t,
        {{"80-step", y - p.at(80), "#2ca02c", false}, {"simulation", y - p.at(0), "#d62728", false}}, "time (s)",
        name + " residual", 900, 220);
  }
  html << demoPoleMap(m);
  html << "<h2>Identification log</h2><pre>";
  for (const auto& l : m.report.lines) html << report::escape(l) << "\n";
  html << "</pre>" << report::chartScript() << "</body></html>\n";
  writeTextFile(path("report.html"), html.str(), "HTML report");
  writePredictionsCsv(m, s, Yv, path("predictions.csv"));
}

void runDemo(const DemoOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const sim::SimConfig config = opt.config.empty() ? sim::SimConfig{} : sim::loadSimConfig(opt.config);
  std::string effects;
  for (const auto& e : sim::effectNames())
    if (config.effectEnabled(e)) effects += (effects.empty() ? "" : ", ") + e;
  std::printf("plsa demo: simulated three-chamber actuator at %.0f Hz, effects on: %s\n", config.sample_rate_hz,
              effects.empty() ? "none" : effects.c_str());
  fs::create_directories(opt.out_dir);
  const OutputFolder path{opt.out_dir};
  for (const char* f : {"train_grid2.csv", "validate_joystick.csv", "model.json", "baseline_paper.json",
                        "baseline_global_linear.json", "fits.json", "report.html"})
    refuseOverwritingInputs(path(f), "--out", {opt.config}, "plsa demo");
  const DemoRuns runs = recordRuns(config, opt.seed, path);
  const DemoModels models = identifyModels(runs.train, sensorDrifts(config), path);
  const DemoScores scores = scoreOnJoystick(models, runs.val);
  writeFits(models, scores, path);
  writeReport(models, scores, runs.val, effects, path);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "\n  wrote %s/{model.json, fits.json, report.html, predictions.csv, train_grid2.csv,\n"
      "    validate_joystick.csv, baseline_paper.json, baseline_global_linear.json} in %.1f s\n",
      opt.out_dir.c_str(), secs);
}

}  // namespace

void addDemoCommand(CLI::App& app) {
  auto opt = std::make_shared<DemoOptions>();
  CLI::App* cmd = app.add_subcommand("demo", "Identify and validate a model on the built-in simulated actuator");
  cmd->add_option("--out", opt->out_dir, "Folder for the model, fits and report")->check(kOutputPath);
  cmd->add_option("--config", opt->config, "Simulator configuration (default: built-in, all effects on)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--seed", opt->seed, "Seed of the simulated runs")->check(kSeed);
  cmd->callback([opt] { runDemo(*opt); });
}

}  // namespace plsa::app
