// `plsa diagnose` (simulator + real runs -> where, which effect, how far) and
// `plsa diagnose-selfcheck` (the same, blind, on data with a withheld effect).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <system_error>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/diagnose/diagnosis.hpp"
#include "plsa/diagnose/selfcheck.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/sim/sim_config.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::app {
namespace {

struct DiagnoseArgs {
  std::string sim;
  std::vector<std::string> real;
  std::string out;
  diagnose::RunColumns columns;
  std::string output_map = "angles";
  std::vector<std::string> pressures = io::standard_columns::pressures();
  diagnose::DiagnoseOptions options;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
};

// Where the report goes, before minutes of calibration: a folder, or none yet.
void checkOutputFolder(const std::string& out) {
  std::error_code ec;
  if (out.empty()) throw std::invalid_argument("plsa diagnose: --out is empty; name the report's folder");
  if (std::filesystem::exists(out, ec) && !std::filesystem::is_directory(out, ec))
    throw std::invalid_argument("plsa diagnose: --out " + out + " exists and is not a folder");
}

void runDiagnose(DiagnoseArgs& a) {
  std::vector<std::string> inputs = a.real;
  inputs.push_back(a.sim);
  inputs.push_back(a.can_profile);
  for (const char* name : diagnose::kDiagnosisFiles)
    refuseOverwritingInputs((std::filesystem::path(a.out) / name).string(), "--out", inputs, "plsa diagnose");
  checkOutputFolder(a.out);
  const sim::SimConfig config = sim::loadSimConfig(a.sim);
  a.columns.map = a.output_map == "affine" ? diagnose::OutputMap::kAffine : diagnose::OutputMap::kAngles;
  a.columns.pressures = a.pressures.size() == 1 && a.pressures[0] == "none" ? std::vector<std::string>{} : a.pressures;
  a.options.calibration.gap.map = a.columns.map;
  // Pressure columns named on the command line must be there (a typo ran
  // the diagnosis without pressures, silently); the default names may be
  // absent, and a note says the gap then compares the outputs alone.
  const bool pressures_named = !a.columns.pressures.empty() && a.pressures != io::standard_columns::pressures();
  std::vector<diagnose::RunData> runs;
  for (const auto& path : logPaths(a.real, "diagnose", false)) {
    io::CsvReadOptions ro;
    ro.required = a.columns.inputs;
    ro.required.insert(ro.required.end(), a.columns.outputs.begin(), a.columns.outputs.end());
    if (pressures_named) ro.required.insert(ro.required.end(), a.columns.pressures.begin(), a.columns.pressures.end());
    ro.lcm_channel = a.channel;
    ro.can_profile = a.can_profile;
    runs.push_back(diagnose::runFromLog(readLogWithWarnings(path, ro, "diagnose"), a.columns, config.max_pressure_bar));
    if (!a.columns.pressures.empty() && !runs.back().hasPressures())
      std::fprintf(stderr,
                   "plsa diagnose: note: %s has no pressure columns %s: its gap compares the outputs alone "
                   "(--pressures names other columns; --pressures none says so)\n",
                   path.c_str(), io::columnList(a.columns.pressures).c_str());
  }
  a.options.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const diagnose::Diagnosis d = diagnose::runDiagnosis(config, runs, a.options);
  diagnose::writeDiagnosisFolder(d, a.out);
  std::printf("%s\n", d.verdict.c_str());
  for (const auto& n : d.notes) std::printf("note: %s\n", n.c_str());
  std::printf("where (held out, after nominal calibration):\n");
  for (const auto& p : d.where.top_places) std::printf("  %s\n", p.words.c_str());
  std::printf("ranking (held-out gap %.1f%% before):\n", d.gap_before.percent());
  for (const auto& c : d.ranking)
    std::printf("  %-14s %-18s -> %5.1f%%  shrink %5.1f%%%s\n", c.effect.c_str(), ("(" + c.formulation + ")").c_str(),
                c.heldout_after.percent(), c.shrink_percent, c.signature.present ? "  (signature supports it)" : "");
  std::printf(
      "wrote %s/diagnosis.json, report.html (with trace.csv, gap_map.csv, shrink.csv), calibrated_sim.json (%.0f s)\n",
      a.out.c_str(), d.elapsed_s);
}

struct SelfcheckArgs {
  diagnose::SelfcheckOptions options;
  bool no_pairs = false;
  std::string out;
};

void runSelfcheckCommand(SelfcheckArgs& a) {
  if (a.no_pairs) a.options.pairs.clear();
  a.options.log = [](const std::string& line) { std::fprintf(stderr, "%s\n", line.c_str()); };
  const diagnose::SelfcheckResult r = diagnose::runSelfcheck(a.options);
  std::printf("%s", r.summary().c_str());
  if (!a.out.empty()) {
    nlohmann::json j;
    j["cases"] = nlohmann::json::array();
    for (const auto& c : r.cases)
      j["cases"].push_back({{"name", c.name},
                            {"withheld", c.withheld},
                            {"formulation", c.formulation},
                            {"selected", c.selected},
                            {"top2", c.top2},
                            {"gap_before", c.gap_before},
                            {"gap_after", c.gap_after},
                            {"noise", c.noise},
                            {"true_effect_shrink", c.true_effect_shrink},
                            {"true_effect_shrink_above_noise", c.true_effect_shrink_above_noise},
                            {"spurious", c.spurious},
                            {"verdict", c.verdict},
                            {"confidence", c.confidence},
                            {"effect_size_percent", c.effect_size},
                            {"truth", c.truth},
                            {"pass", c.pass},
                            {"elapsed_s", c.elapsed_s}});
    j["labels"] = r.labels;
    j["confusion"] = r.confusion;
    j["targets_met"] = r.targets_met;
    j["truth"] = r.truth;
    j["excitation"] = r.excitation;
    j["summary"] = {{"single_cases", r.single_cases},
                    {"single_top1", r.single_top1},
                    {"pair_cases", r.pair_cases},
                    {"pair_top2", r.pair_top2},
                    {"pair_both_selected", r.pair_both_selected},
                    {"null_cases", r.null_cases},
                    {"null_clean", r.null_clean},
                    {"cases_with_spurious", r.cases_with_spurious},
                    {"gap_single_cases", r.gap_single_cases},
                    {"gap_single_top1", r.gap_single_top1},
                    {"uncertain", r.uncertain},
                    {"qualified", r.qualified},
                    {"median_true_shrink", r.median_true_shrink},
                    {"min_true_shrink", r.min_true_shrink},
                    {"median_true_shrink_above_noise", r.median_true_shrink_above_noise},
                    {"cases_above_noise", r.cases_above_noise}};
    writeTextFile(a.out, j.dump(2), "self-check results");
  }
  if (!r.targets_met) throw std::runtime_error("diagnose-selfcheck: targets not met (see the table above)");
}

// The simulator runs a diagnosis may spend, as both commands take them.
void addCalibrationBudget(CLI::App* app, diagnose::DiagnoseOptions& o) {
  app->add_option("--evaluations-per-parameter", o.calibration.evaluations_per_parameter,
                  "At least this many simulator runs per calibrated parameter (0: --evaluations alone)")
      ->check(CLI::Range(0, 1000));
  app->add_option("--evaluations", o.calibration.max_evaluations, "Simulator runs per calibration")
      ->check(CLI::Range(20, 100000));
  app->add_option("--screen-evaluations", o.screen_evaluations,
                  "Simulator runs of the short calibration from each spread start of a candidate; the best "
                  "becomes its second start (0: the spread start with the smallest gap)")
      ->check(CLI::Range(0, 10000));
  app->add_flag("--both-starts-in-later-rounds", o.both_starts_in_later_rounds,
                "Later rounds calibrate every candidate from both its starts (default: a candidate that gained "
                "nothing in round 1 from the start that did best for it there)");
  app->add_option("--calibration-step", o.calibration_step_s,
                  "The internal step (s) calibrations run at, or at half of it, where on the calibrated nominal "
                  "physics it moves the training gap by a tenth of the noise floor or less (0: the configured step)")
      ->check(CLI::Range(0.0, 0.01))
      ->capture_default_str();
  app->add_option("--calibration-integrator", o.calibration.coarse_integrator,
                  "The simulator's integrator where calibrations run at a coarser internal step than configured "
                  "(every reported gap is measured at the configured step and integrator)")
      ->check(CLI::IsMember(sim::integratorNames()))
      ->capture_default_str();
}

void addDiagnoseCommand(CLI::App& app) {
  auto a = std::make_shared<DiagnoseArgs>();
  CLI::App* c =
      app.add_subcommand("diagnose", "Where and why a simulator disagrees with real runs, and what fixing it buys");
  c->add_option("--sim", a->sim, "Simulator configuration (JSON; its switched-off effects are the candidates)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--real", a->real,
                "Real run(s): CSV or LCM event logs (known by content); several: split by run, one: split by time")
      ->required()
      ->check(CLI::ExistingFile);
  addLogFormatOptions(c, a->channel, a->can_profile);
  c->add_option("--out", a->out, "Output directory (diagnosis.json, report.html, calibrated_sim.json)")
      ->required()
      ->check(kOutputPath);
  c->add_option("--inputs", a->columns.inputs, "Chamber command columns (1-3)")->delimiter(',');
  c->add_option("--outputs", a->columns.outputs, "Two output columns")->delimiter(',');
  c->add_option("--pressures", a->pressures, "Measured chamber pressure columns, or 'none'")->delimiter(',');
  c->add_option("--input-scale", a->columns.input_scale, "Bar per input unit")->check(kPositive);
  c->add_option(
       "--output-map", a->output_map,
       "angles (outputs are bend, steer in deg) or affine (an unknown affine image of the bending vector, fitted)")
      ->check(CLI::IsMember({"angles", "affine"}));
  c->add_option("--candidates", a->options.candidates, "Effects to try (default: every one switched off)")
      ->delimiter(',');
  c->add_flag(
      "--fixed-laws", [a](std::int64_t n) { a->options.flexible_laws = n == 0; },
      "Calibrate each candidate with the formulation its configuration names, instead of its flexible "
      "law (stiffening and pneumatic_lag: a power law spanning the fixed ones)");
  addCalibrationBudget(c, a->options);
  c->add_option("--margin", a->options.margin, "An effect must shrink the held-out gap by this many noise floors")
      ->check(kNonNegative);
  c->add_option("--heldout-fraction", a->options.heldout_fraction, "With one run: the share held out at its end")
      ->check(finiteNumber() & CLI::Range(0.05, 0.95));
  c->add_option("--threads", a->options.threads, "Candidates calibrated in parallel")->check(CLI::Range(1, 64));
  c->add_flag(
      "--no-identified-reference", [a](std::int64_t n) { a->options.identified_reference = n == 0; },
      "Skip the held-out gap of a plsa model identified on the training runs (reported beside the verdict; on "
      "three 60 s runs about half a diagnosis's CPU time, bench/README.md)");
  c->callback([a] { runDiagnose(*a); });
}

void addSelfcheckCommand(CLI::App& app) {
  auto s = std::make_shared<SelfcheckArgs>();
  CLI::App* sc = app.add_subcommand("diagnose-selfcheck", "Score the diagnosis blind on data with withheld effects");
  sc->add_option_function<std::string>(
        "--truth",
        [s](const std::string& t) {
          s->options.truth = t == "own" ? diagnose::SelfcheckTruth::kOwnLaws : diagnose::SelfcheckTruth::kIndependent;
        },
        "independent (default): \"real\" data from a simulator written apart from plsa's, laws outside every "
        "candidate's family, nominal physics randomised widely; own: plsa's simulator and its formulations (a "
        "check of the machinery, not of generalisation)")
      ->check(CLI::IsMember({"independent", "own"}));
  sc->add_option_function<std::string>(
        "--excitation",
        [s](const std::string& e) {
          s->options.excitation = e == "joystick" ? diagnose::SelfcheckExcitation::kJoystick
                                                  : diagnose::SelfcheckExcitation::kHoldsAndRamps;
        },
        "holds (default): random multi-chamber holds of 0.6-3 s, some ramped; joystick: a two-axis joystick moved "
        "by hand at about 0.3 Hz, one or two chambers at a time")
      ->check(CLI::IsMember({"holds", "joystick"}));
  sc->add_flag(
      "--settled", [s](std::int64_t n) { s->options.from_rest = n == 0; },
      "own laws: record the runs settled at their first command instead of from rest");
  sc->add_option("--effects", s->options.effects, "Single-effect cases (default: all seven)")->delimiter(',');
  sc->add_flag(
      "--fixed-laws", [s](std::int64_t n) { s->options.diagnose.flexible_laws = n == 0; },
      "Diagnose with each candidate's configured formulation instead of its flexible law");
  sc->add_option("--seeds", s->options.seeds_per_effect,
                 "Cases per effect (independent: its laws outside the candidate's family in turn; own: odd ones with a "
                 "law the candidate's "
                 "cannot express); default 4")
      ->check(CLI::Range(1, 20));
  sc->add_flag("--no-pairs", s->no_pairs, "Skip the pairs of withheld effects");
  sc->add_option("--null", s->options.null_cases, "Null cases (nothing withheld)")->check(CLI::Range(0, 20));
  sc->add_option("--seed", s->options.seed, "First seed")->check(kSeed);
  sc->add_option("--train-s", s->options.train_s, "Training run length (s)")->check(CLI::Range(10.0, 600.0));
  sc->add_option("--heldout-s", s->options.heldout_s, "Held-out run length (s)")->check(CLI::Range(10.0, 600.0));
  addCalibrationBudget(sc, s->options.diagnose);
  sc->add_option("--threads", s->options.diagnose.threads, "Candidates calibrated in parallel")
      ->check(CLI::Range(1, 64));
  sc->add_option("--out", s->out, "Results as JSON")->check(kOutputPath);
  sc->add_flag("--verbose", s->options.verbose, "Show each diagnosis's progress");
  sc->add_option("--save-runs", s->options.save_runs_dir,
                 "Write every case's training and held-out runs to this directory as CSV logs (for plsa diagnose)")
      ->check(CLI::ExistingDirectory);
  sc->callback([s] { runSelfcheckCommand(*s); });
}

}  // namespace

void addDiagnoseCommands(CLI::App& app) {
  addDiagnoseCommand(app);
  addSelfcheckCommand(app);
}

}  // namespace plsa::app
