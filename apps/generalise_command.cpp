// `plsa generalise`: identification scored on physics plsa did not write.
// Each case is the independently written actuator (sim::IndependentActuator)
// under one law of one effect (or none, or every effect at once), its
// nominal physics randomised widely per seed; the paper's grid run and a
// joystick run are recorded from rest, as a user records them. plsa's model
// (identify's defaults), the paper's configuration, the global linear OBF and
// ARX(4,4) are fitted on the grid run and scored on the joystick run, every
// model, output and horizon on the same samples. The whole matrix is printed
// and written as JSON; nothing is averaged away.
#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "plsa/eval/comparison.hpp"
#include "plsa/identify/baselines.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/identify/output_drift.hpp"
#include "plsa/identify/pipeline.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/io/standard_columns.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/independent_actuator.hpp"
#include "plsa/sim/independent_recording.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::app {
namespace {

struct GeneraliseArgs {
  int seeds = 3;
  std::uint64_t seed = 1;
  std::vector<std::string> cases;  // "effect.law", "nominal", "all"; empty: every law of every effect, both extremes
  bool quick = false;
  std::string json;
  std::string save_runs;  // folder for every case's runs as CSV logs; empty: none
};

/// One physics: the effects switched on, each with its law.
struct PhysicsCase {
  std::string name;
  std::vector<std::pair<std::string, std::string>> effects;  // effect, law
  double bend_range_deg = 0.0;  ///< the grid run's largest bend, the lever rescaled to it; 0: as drawn
};

/// Bending ranges beside the drawn ones (about 15-25 deg over the grid): a
/// nearly straight segment, where the sensor's noise weighs most, and ones
/// bending far, where the tip direction turns through large angles.
constexpr double kBendRangesDeg[] = {2.0, 50.0, 100.0};

const char* kModels[] = {"plsa", "paper", "global_linear", "arx"};
const std::vector<int> kHorizons = {40, 80};
/// The run beyond the grid: a joystick over 0.10-0.45 bar (the grid spans 0.20-0.35).
constexpr double kBeyondMinBar = 0.10, kBeyondMaxBar = 0.45;

std::vector<PhysicsCase> listCases(const GeneraliseArgs& a) {
  std::vector<PhysicsCase> all = {{"nominal", {}}};
  for (const std::string& e : sim::effectNames())
    for (const std::string& law : sim::independentLawsOf(e)) all.push_back({e + "." + law, {{e, law}}});
  PhysicsCase every{"all", {}};
  for (const std::string& e : sim::effectNames()) every.effects.push_back({e, sim::independentLawsOf(e).front()});
  all.push_back(every);
  for (const PhysicsCase& base : {all.front(), every})
    for (const double range : kBendRangesDeg) {
      PhysicsCase c = base;
      c.name = base.name + "@" + std::to_string(static_cast<int>(range)) + "deg";
      c.bend_range_deg = range;
      all.push_back(c);
    }
  std::vector<std::string> wanted = a.cases;
  if (a.quick) wanted = {"nominal", "hysteresis.bouc_wen", "all"};
  if (wanted.empty()) return all;
  std::vector<PhysicsCase> out;
  for (const std::string& w : wanted) {
    const auto it = std::find_if(all.begin(), all.end(), [&](const PhysicsCase& c) { return c.name == w; });
    if (it == all.end()) {
      std::string names;
      for (const PhysicsCase& c : all) names += (names.empty() ? "" : ", ") + c.name;
      throw std::invalid_argument("generalise: no case '" + w + "'; the cases are " + names);
    }
    out.push_back(*it);
  }
  return out;
}

/// The case's physics: nominal parts randomised widely, each effect at a strength drawn from its range.
sim::IndependentPhysics drawPhysics(const PhysicsCase& c, std::mt19937_64& rng, nlohmann::json& drawn) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  sim::IndependentPhysics t;
  for (const auto& [name, value] : sim::drawNominal(t, rng)) drawn[name] = value;
  for (const auto& [effect, law] : c.effects) {
    const auto [lo, hi] = sim::independentStrengthRange(effect, law);
    const double strength = lo + (hi - lo) * uni(rng);
    sim::setIndependentEffect(t, effect, law, strength);
    drawn[effect + "." + law] = strength;
  }
  // One mount for the case: its training and validation runs read the same
  // offset direction (drawn after the strengths, so they stay as they were).
  const bool biased =
      std::any_of(c.effects.begin(), c.effects.end(), [](const auto& e) { return e.first == "sensor_bias"; });
  if (biased) drawn["sensor_offset_direction_deg"] = t.sensor_offset_direction_deg = 360.0 * uni(rng);
  return t;
}

/// plsa's model on a run beyond its grid: the share of its samples beyond,
/// and each output's fits (every horizon and the simulation on the same samples).
nlohmann::json scoreBeyond(const DioPwlObfModel& model, const io::Log& run) {
  const Eigen::MatrixXd U = run.columnsOf(model.inputs), Y = run.columnsOf(model.outputs);
  const std::vector<eval::ModelPredictions> preds = {eval::predictDio("plsa", model, U, Y, kHorizons)};
  const auto scores = eval::commonScores(preds, Y);
  nlohmann::json j = {{"beyond_grid", eval::inputsOutsideTraining(model, U).any_beyond_grid}};
  for (std::size_t out = 0; out < model.outputs.size(); ++out)
    for (const int h : {40, 80, 0})
      j["plsa"][model.outputs[out]][h == 0 ? "sim" : std::to_string(h)] = scores[0][out].at(h).fit;
  return j;
}

/// The validation run's noise-free outputs as a "model" predicting them at
/// every horizon, to be scored like the others.
eval::ModelPredictions noiseFreeReading(const Eigen::MatrixXd& outputs) {
  eval::ModelPredictions p{"noise_free", {}};
  for (Eigen::Index out = 0; out < outputs.cols(); ++out) {
    std::map<int, Eigen::VectorXd> by_horizon;
    for (const int h : kHorizons) by_horizon[h] = outputs.col(out);
    by_horizon[0] = outputs.col(out);
    p.by_output.push_back(std::move(by_horizon));
  }
  return p;
}

/// Every model fitted on `train` and scored on `val` over the same samples:
/// [model][output] -> {horizon (0: simulation): fit %}, as JSON; plsa also on
/// `wide`, a run beyond its grid, under "beyond"; and under "noise_free",
/// per output, the fit of `val_noise_free` (the validation run's outputs
/// without the sensor's white noise) over the same samples: the ceiling the
/// noise leaves any model.
nlohmann::json scoreModels(const io::Log& train, const io::Log& val, const Eigen::MatrixXd& val_noise_free,
                           const io::Log& wide, double& beyond_grid) {
  identify::IdentifyOptions o;
  identify::IdentifyReport report;
  const DioPwlObfModel model = identify::identifyModel({train}, o, &report);
  const DioPwlObfModel paper = identify::identifyModel({train}, identify::paperConfiguration(o));
  const identify::BaselineData training = identify::baselineData(model, report, {train});
  const DioPwlObfModel linear = identify::globalLinearOf(model, training);
  const eval::ArxModel arx = eval::ArxModel::fit(training.U, training.Y, 4, 4);
  const Eigen::MatrixXd Uv = val.columnsOf(model.inputs), Yv = val.columnsOf(model.outputs);
  beyond_grid = eval::inputsOutsideTraining(model, Uv).any_beyond_grid;
  const std::vector<double> arx_drift = report.drift_taken_out ? report.output_drift.rate : std::vector<double>{};
  const std::vector<eval::ModelPredictions> preds = {
      eval::predictDio("plsa", model, Uv, Yv, kHorizons), eval::predictDio("paper", paper, Uv, Yv, kHorizons),
      eval::predictDio("global_linear", linear, Uv, Yv, kHorizons),
      eval::predictArx("arx", arx, Uv, Yv, kHorizons, arx_drift, model.sample_time_s),
      noiseFreeReading(val_noise_free)};
  const auto scores = eval::commonScores(preds, Yv);
  nlohmann::json j;
  const Eigen::Index from = eval::commonScoringStart(preds);
  j["scored_from_sample"] = from;
  for (std::size_t m = 0; m < std::size(kModels); ++m)
    for (std::size_t out = 0; out < model.outputs.size(); ++out)
      for (const int h : {40, 80, 0})
        j[kModels[m]][model.outputs[out]][h == 0 ? "sim" : std::to_string(h)] = scores[m][out].at(h).fit;
  for (std::size_t out = 0; out < model.outputs.size(); ++out)
    j["noise_free"][model.outputs[out]] = scores.back()[out].at(0).fit;
  for (std::size_t out = 0; out < model.outputs.size(); ++out)
    j["plsa_sim_error_kept_80"][model.outputs[out]] =
        eval::simulationErrorKept(Yv.col(static_cast<Eigen::Index>(out)), preds[0].by_output[out].at(0), from, 80);
  j["beyond"] = scoreBeyond(model, wide);
  return j;
}

/// One model's fits on one output ({"40", "80", "sim"}) as table text.
std::string cell(const nlohmann::json& s) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%5.1f %5.1f %6.1f", s.at("40").get<double>(), s.at("80").get<double>(),
                s.at("sim").get<double>());
  return buf;
}

void printRow(const nlohmann::json& row) {
  const nlohmann::json& ceiling = row.at("fits").at("noise_free");
  std::printf("  %-32s %4d %5.1f%% %5.1f %5.1f", row.at("case").get<std::string>().c_str(), row.at("seed").get<int>(),
              100 * row.at("beyond_grid").get<double>(), ceiling.at(io::standard_columns::kBend).get<double>(),
              ceiling.at(io::standard_columns::kSteer).get<double>());
  for (const char* m : kModels)
    std::printf(" | %s  %s", cell(row.at("fits").at(m).at(io::standard_columns::kBend)).c_str(),
                cell(row.at("fits").at(m).at(io::standard_columns::kSteer)).c_str());
  std::printf("\n");
}

/// Over every row and output: where plsa's 80-step fit falls below its
/// simulation's, and whether the simulation error kept over 80 samples
/// (eval::simulationErrorKept) says so by being under 1/2.
nlohmann::json anchoringCounts(const nlohmann::json& rows) {
  int below = 0, below_kept_under_half = 0, above = 0, above_kept_over_half = 0;
  for (const auto& r : rows)
    for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer}) {
      const nlohmann::json& f = r.at("fits").at("plsa").at(out);
      const nlohmann::json& k = r.at("fits").at("plsa_sim_error_kept_80").at(out);
      const double kept = k.is_number() ? k.get<double>() : NAN;  // null: no simulation error at all
      if (f.at("80").get<double>() < f.at("sim").get<double>()) {
        ++below;
        below_kept_under_half += kept < 0.5 ? 1 : 0;
      } else {
        ++above;
        above_kept_over_half += kept >= 0.5 ? 1 : 0;
      }
    }
  return {{"outputs", below},
          {"with_error_kept_under_half", below_kept_under_half},
          {"other_outputs", above},
          {"other_with_error_kept_over_half", above_kept_over_half}};
}

/// plsa on the runs beyond the grid: the mean share of samples beyond, and
/// per output and horizon the mean and worst fit, beside the same rows' means inside.
nlohmann::json beyondSummary(const nlohmann::json& rows) {
  nlohmann::json s;
  double share = 0.0;
  for (const auto& r : rows) share += r.at("fits").at("beyond").at("beyond_grid").get<double>();
  s["beyond_grid_mean"] = share / static_cast<double>(rows.size());
  for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer})
    for (const char* h : {"40", "80", "sim"}) {
      double sum = 0.0, worst = 1e300, inside = 0.0;
      for (const auto& r : rows) {
        const double f = r.at("fits").at("beyond").at("plsa").at(out).at(h).get<double>();
        sum += f;
        worst = std::min(worst, f);
        inside += r.at("fits").at("plsa").at(out).at(h).get<double>();
      }
      const double n = static_cast<double>(rows.size());
      s[out][h] = {{"mean", sum / n}, {"worst", worst}, {"mean_inside", inside / n}};
    }
  return s;
}

void printBeyondRows(const nlohmann::json& rows) {
  std::printf("\n  plsa's model of each row on a joystick run beyond the grid (%.2f-%.2f bar; the grid: 0.20-0.35)\n",
              kBeyondMinBar, kBeyondMaxBar);
  std::printf("  %-32s %4s %6s | %-39s\n", "case", "seed", "beyond", "plsa (bend 40 80 sim, steer)");
  for (const auto& r : rows) {
    const nlohmann::json& b = r.at("fits").at("beyond");
    std::printf("  %-32s %4d %5.1f%% | %s  %s\n", r.at("case").get<std::string>().c_str(), r.at("seed").get<int>(),
                100 * b.at("beyond_grid").get<double>(), cell(b.at("plsa").at(io::standard_columns::kBend)).c_str(),
                cell(b.at("plsa").at(io::standard_columns::kSteer)).c_str());
  }
}

/// Whether plsa's model reaches 90 / 90 / 85 (40 steps, 80 steps,
/// simulation) on both outputs of a row.
bool plsaMeetsTargets(const nlohmann::json& row) {
  for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer}) {
    const nlohmann::json& f = row.at("fits").at("plsa").at(out);
    if (f.at("40").get<double>() < 90 || f.at("80").get<double>() < 90 || f.at("sim").get<double>() < 85) return false;
  }
  return true;
}

/// Whether the sensor's white noise leaves room for those targets: the
/// noise-free reading itself fits the measured one to 90 on both outputs.
bool noiseAllowsTargets(const nlohmann::json& row) {
  const nlohmann::json& c = row.at("fits").at("noise_free");
  return c.at(io::standard_columns::kBend).get<double>() >= 90 &&
         c.at(io::standard_columns::kSteer).get<double>() >= 90;
}

/// Per model and output: the mean and the worst of each horizon's fit over every row.
nlohmann::json summarise(const nlohmann::json& rows) {
  nlohmann::json s;
  for (const char* m : kModels)
    for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer})
      for (const char* h : {"40", "80", "sim"}) {
        double sum = 0.0, worst = 1e300;
        for (const auto& r : rows) {
          const double f = r.at("fits").at(m).at(out).at(h).get<double>();
          sum += f;
          worst = std::min(worst, f);
        }
        s[m][out][h] = {{"mean", sum / static_cast<double>(rows.size())}, {"worst", worst}};
      }
  s["plsa_rows_meeting_90_90_85"] = std::count_if(rows.begin(), rows.end(), plsaMeetsTargets);
  s["rows_noise_allows_90"] = std::count_if(rows.begin(), rows.end(), noiseAllowsTargets);
  s["plsa_rows_meeting_90_90_85_where_noise_allows"] = std::count_if(
      rows.begin(), rows.end(), [](const nlohmann::json& r) { return noiseAllowsTargets(r) && plsaMeetsTargets(r); });
  s["rows"] = rows.size();
  s["plsa_80_below_sim"] = anchoringCounts(rows);
  s["plsa_beyond"] = beyondSummary(rows);
  return s;
}

void printSummary(const nlohmann::json& s) {
  std::printf("\n  mean (worst) over %zu rows, 40-step / 80-step / sim:\n", s.at("rows").get<std::size_t>());
  for (const char* m : kModels)
    for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer}) {
      std::printf("  %-14s %-10s", m, out);
      for (const char* h : {"40", "80", "sim"})
        std::printf("  %6.1f (%6.1f)", s[m][out][h]["mean"].get<double>(), s[m][out][h]["worst"].get<double>());
      std::printf("\n");
    }
  std::printf(
      "  plsa meets 90 / 90 / 85 on both outputs in %d of %zu rows; the sensor's white noise leaves room\n"
      "  for it (the noise-free reading fits the measured one to 90 on both outputs) in %d rows, and plsa\n"
      "  meets it in %d of those\n",
      s.at("plsa_rows_meeting_90_90_85").get<int>(), s.at("rows").get<std::size_t>(),
      s.at("rows_noise_allows_90").get<int>(), s.at("plsa_rows_meeting_90_90_85_where_noise_allows").get<int>());
  const nlohmann::json& b = s.at("plsa_beyond");
  std::printf(
      "  beyond the grid (%.0f%% of the run's samples beyond it, mean), plsa's mean (worst) 40-step / 80-step / sim,\n"
      "  and its mean inside:\n",
      100 * b.at("beyond_grid_mean").get<double>());
  for (const char* out : {io::standard_columns::kBend, io::standard_columns::kSteer}) {
    std::printf("  %-14s %-10s", "plsa beyond", out);
    for (const char* h : {"40", "80", "sim"})
      std::printf("  %6.1f (%6.1f)", b[out][h]["mean"].get<double>(), b[out][h]["worst"].get<double>());
    std::printf("   inside %.1f / %.1f / %.1f\n", b[out]["40"]["mean_inside"].get<double>(),
                b[out]["80"]["mean_inside"].get<double>(), b[out]["sim"]["mean_inside"].get<double>());
  }
  const nlohmann::json& a = s.at("plsa_80_below_sim");
  std::printf(
      "  plsa's 80-step fit is below its simulation's on %d row outputs; the simulation error kept over 80 samples\n"
      "  is under 0.5 on %d of them, and at least 0.5 on %d of the other %d (a k-step prediction restarts from the\n"
      "  measured output and carries the model's error there: validate's 'error kept', docs/validation.md)\n",
      a.at("outputs").get<int>(), a.at("with_error_kept_under_half").get<int>(),
      a.at("other_with_error_kept_over_half").get<int>(), a.at("other_outputs").get<int>());
}

/// A case's training (grid) and validation (joystick, and joystick beyond the
/// grid) runs as CSV logs that identify and validate read:
/// DIR/CASE_sSEED_{grid2,joystick,joystick_beyond}.csv.
void saveRuns(const std::string& dir, const std::string& case_name, std::uint64_t seed,
              const std::array<io::Log, 3>& runs) {
  const std::string stem = (std::filesystem::path(dir) / (case_name + "_s" + std::to_string(seed))).string();
  const char* names[] = {"_grid2.csv", "_joystick.csv", "_joystick_beyond.csv"};
  for (std::size_t r = 0; r < runs.size(); ++r) io::writeCsvLog(stem + names[r], runs[r]);
}

void runGeneralise(const GeneraliseArgs& a) {
  const std::vector<PhysicsCase> cases = listCases(a);
  const int seeds = a.quick ? 1 : a.seeds;
  std::printf(
      "plsa generalise: %zu cases x %d seeds on the independent actuator, recorded from rest; fit %% on the\n"
      "joystick run, every model and horizon on the same samples; beyond: share of its samples beyond plsa's grid;\n"
      "noise-free: the fit of the run's outputs without the sensor's white noise (bend, steer), the most any model\n"
      "can reach\n",
      cases.size(), seeds);
  std::printf("  %-32s %4s %6s %-11s | %-39s | %-39s | %-39s | %-39s\n", "case", "seed", "beyond", " noise-free",
              "plsa (bend 40 80 sim, steer)", "paper", "global linear OBF", "ARX(4,4)");
  nlohmann::json rows = nlohmann::json::array();
  const auto t0 = std::chrono::steady_clock::now();
  for (const PhysicsCase& c : cases)
    for (int s = 0; s < seeds; ++s) {
      const std::uint64_t seed = a.seed + static_cast<std::uint64_t>(s);
      std::mt19937_64 rng(seed * 7919 + std::hash<std::string>{}(c.name));
      nlohmann::json row = {{"case", c.name}, {"seed", seed}};
      sim::IndependentPhysics physics = drawPhysics(c, rng, row["physics"]);
      sim::ExperimentOptions eo;
      eo.seed = seed + 1;
      const sim::Experiment grid = sim::gridExperiment(eo);
      row["bend_range_deg"] = c.bend_range_deg > 0 ? sim::scaleToBendRange(physics, grid.commands, c.bend_range_deg)
                                                   : sim::largestBendDeg(physics, grid.commands);
      const io::Log train = sim::recordIndependentFromRest(physics, grid, seed);
      Eigen::MatrixXd val_noise_free;
      const io::Log val =
          sim::recordIndependentFromRest(physics, sim::joystickExperiment(eo), seed + 100, &val_noise_free);
      sim::ExperimentOptions wide_eo = eo;  // a joystick run well beyond the grid's 0.20-0.35 bar
      wide_eo.joystick_min_bar = kBeyondMinBar;
      wide_eo.joystick_max_bar = kBeyondMaxBar;
      const io::Log wide = sim::recordIndependentFromRest(physics, sim::joystickExperiment(wide_eo), seed + 200);
      if (!a.save_runs.empty()) saveRuns(a.save_runs, c.name, seed, {train, val, wide});
      double beyond = 0.0;
      row["fits"] = scoreModels(train, val, val_noise_free, wide, beyond);
      row["beyond_grid"] = beyond;
      printRow(row);
      rows.push_back(row);
    }
  const nlohmann::json summary = summarise(rows);
  printBeyondRows(rows);
  printSummary(summary);
  std::printf("  %.0f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  if (!a.json.empty())
    writeTextFile(a.json, nlohmann::json{{"rows", rows}, {"summary", summary}}.dump(1) + "\n",
                  "generalisation results");
}

}  // namespace

void addGeneraliseCommand(CLI::App& app) {
  auto a = std::make_shared<GeneraliseArgs>();
  CLI::App* cmd = app.add_subcommand(
      "generalise",
      "Identification scored on an independently written actuator: every law of every effect, "
      "nominal physics randomised, recorded from rest; plsa against the paper, global linear OBF and ARX, "
      "and plsa on a run beyond its grid");
  cmd->add_option("--seeds", a->seeds, "Physics drawn per case")->check(CLI::Range(1, 100));
  cmd->add_option("--seed", a->seed, "First seed")->check(kSeed);
  cmd->add_option("--case", a->cases,
                  "Cases to run (effect.law, nominal or all, or nominal@Ndeg / all@Ndeg for N in 2, 50, 100: the "
                  "segment's lever rescaled so that the grid run bends at most N deg; default every one)");
  cmd->add_flag("--quick", a->quick, "Three cases (nominal, hysteresis.bouc_wen, all), one seed");
  cmd->add_option("--json", a->json, "Write every row and the summary here")->check(kOutputPath);
  cmd->add_option("--save-runs", a->save_runs,
                  "Write every case's training and validation runs to this directory as CSV logs "
                  "(CASE_sSEED_grid2.csv, CASE_sSEED_joystick.csv, CASE_sSEED_joystick_beyond.csv; for plsa identify "
                  "and validate)")
      ->check(CLI::ExistingDirectory);
  cmd->callback([a] { runGeneralise(*a); });
}

}  // namespace plsa::app
