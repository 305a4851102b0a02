// The plsa tool as a user runs it: files in, files out, clear errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "plsa/eval/fit.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/model_file.hpp"
#include "support/cli_run.hpp"

namespace fs = std::filesystem;

namespace {
using Cli = plsa::test::CliTest;
}  // namespace

TEST_F(Cli, SimulateIsDeterministicPerSeed) {
  ASSERT_EQ(run("simulate --experiment joystick --duration 5 --seed 7 --out " + file("a.csv")), 0) << err_;
  ASSERT_EQ(run("simulate --experiment joystick --duration 5 --seed 7 --out " + file("b.csv")), 0) << err_;
  ASSERT_EQ(run("simulate --experiment joystick --duration 5 --seed 8 --out " + file("c.csv")), 0) << err_;
  EXPECT_EQ(slurp(file("a.csv")), slurp(file("b.csv")));
  EXPECT_NE(slurp(file("a.csv")), slurp(file("c.csv")));
  ASSERT_EQ(run("simulate --experiment staircase1 --duration 30 --seed 7 --out " + file("s.lcmlog")), 0) << err_;
  EXPECT_GT(fs::file_size(file("s.lcmlog")), 1000u);
}

// --duration is what the log holds: the unrecorded pre-roll is not counted,
// and too short a duration is refused by name.
TEST_F(Cli, SimulateRecordsTheDurationAsked) {
  const auto samples = [&](const std::string& path) {
    std::istringstream in(slurp(path));
    int rows = 0;
    for (std::string l; std::getline(in, l);) rows += !l.empty() && l[0] != '#';
    return rows - 1;  // the header
  };
  for (const std::string e : {"grid2", "staircase1"}) {
    ASSERT_EQ(run("simulate --experiment " + e + " --duration 100 --out " + file(e + ".csv")), 0) << err_;
    EXPECT_NEAR(samples(file(e + ".csv")), 8000, 40) << e;  // a hold rounds to whole samples
    EXPECT_NE(err_.find(e + ", 100.0 s recorded at 80 Hz"), std::string::npos) << err_;
  }
  ASSERT_EQ(run("simulate --experiment joystick --duration 20 --out " + file("j.csv")), 0) << err_;
  EXPECT_EQ(samples(file("j.csv")), 1680);  // 1 s held at the start, then 20 s moving
  EXPECT_EQ(run("simulate --experiment grid2 --duration 1 --out " + file("short.csv")), 1);
  EXPECT_NE(err_.find("too short for grid2"), std::string::npos) << err_;
  EXPECT_EQ(run("simulate --experiment static_map --duration 100 --out " + file("map.csv")), 1);
  EXPECT_NE(err_.find("--duration does not apply to static_map"), std::string::npos) << err_;
}

TEST_F(Cli, IdentifyThenValidateWritesFitsJson) {
  ASSERT_EQ(run("simulate --experiment grid2 --seed 1 --out " + file("train.csv")), 0) << err_;
  ASSERT_EQ(run("simulate --experiment joystick --duration 30 --seed 2 --out " + file("val.lcmlog")), 0) << err_;
  ASSERT_EQ(run("identify --log " + file("train.csv") +
                " --output-frame tip_cartesian --play-coupling 0.3 "
                "--play-threshold 0.2 --output-drift auto --out " +
                file("model.json")),
            0)
      << err_;
  EXPECT_NE(err_.find("[5/5] coefficients"), std::string::npos) << "progress lines missing: " << err_;
  // The candidates given are the ones tried: coupling 0.3 only, threshold 0.2 only.
  const auto line = [&](const std::string& head) {
    const std::size_t at = err_.find(head);
    return at == std::string::npos ? std::string() : err_.substr(at, err_.find('\n', at) - at);
  };
  const std::string coupling = line("[5/5] coupled to the other inputs"),
                    threshold = line("[5/5] play channels counted");
  EXPECT_NE(coupling.find(" 0.30{"), std::string::npos) << coupling;
  EXPECT_EQ(coupling.find(" 0.15{"), std::string::npos) << coupling;
  EXPECT_NE(threshold.find(" 0.2/"), std::string::npos) << threshold;
  EXPECT_EQ(threshold.find(" 0.1/"), std::string::npos) << threshold;
  // The drift stage says what it did (input side) or why not (output side);
  // in the tip frame a drift is one yaw rate, never the bending's.
  const std::string drift = line("[5/5] sensor drift");
  EXPECT_FALSE(drift.empty()) << err_;
  // (The scores after the rates name each output: taking a yaw out moves both.)
  EXPECT_EQ(drift.substr(0, drift.find(" (held-out")).find("bend_deg "), std::string::npos) << drift;
  EXPECT_EQ(nlohmann::json::parse(slurp(file("model.json")))["output_frame"], "tip_cartesian");
  ASSERT_EQ(run("validate --model " + file("model.json") + " --log " + file("val.lcmlog") +
                " --horizons 40,80 --json " + file("fits.json") + " --csv " + file("pred.csv")),
            0)
      << err_;
  const auto j = nlohmann::json::parse(slurp(file("fits.json")));
  for (const std::string out : {"bend_deg", "steer_deg"})
    for (const std::string key : {"fit_k40", "fit_k80", "fit_sim"}) {
      ASSERT_TRUE(j["outputs"][out].contains(key)) << out << "." << key;
      EXPECT_TRUE(j["outputs"][out][key].is_number());
    }
  // Errors in degrees beside the fits: every fit, error and the spread on
  // the same samples, so each fit is 100 (1 - rms / std).
  const plsa::io::Log pred_log = plsa::io::readCsvLog(file("pred.csv"));
  const Eigen::MatrixXd& pred = pred_log.data;
  ASSERT_TRUE(j.contains("scored_samples")) << j.dump();
  EXPECT_EQ(j["scored_samples"]["count"].get<long>(), pred.rows()) << "the CSV holds the scored samples";
  for (const std::string out : {"bend_deg", "steer_deg"}) {
    const auto& o = j["outputs"][out];
    for (const std::string key : {"rms_k40", "rms_k80", "rms_sim", "std"}) {
      ASSERT_TRUE(o.contains(key)) << out << "." << key;
      EXPECT_GT(o[key].get<double>(), 0.0) << out << "." << key;
    }
    EXPECT_LT(o["rms_k40"].get<double>(), o["std"].get<double>()) << out;
    for (const std::string h : {"k40", "k80", "sim"}) {
      EXPECT_NEAR(o["fit_" + h].get<double>(), 100.0 * (1.0 - o["rms_" + h].get<double>() / o["std"].get<double>()),
                  1e-6)
          << out << " " << h;
      // ...and the same fit recomputed from the written predictions.
      EXPECT_NEAR(o["fit_" + h].get<double>(),
                  plsa::eval::nrmseFit(pred_log.column(out), pred_log.column(out + "_" + h)), 1e-6)
          << out << " " << h;
    }
  }
  const std::string printed = slurp(file("stdout.txt"));
  EXPECT_NE(printed.find("measured std"), std::string::npos) << printed;
  // A model whose simulation diverges (one coefficient of 1e150, a hostile
  // file) is scored and warned about, its table still a table: no cell of
  // 150 digits.
  auto wild = nlohmann::json::parse(slurp(file("model.json")));
  wild["regions"][0]["coefficients"][0][3] = 1e150;
  std::ofstream(file("wild.json")) << wild.dump();
  ASSERT_EQ(run("validate --model " + file("wild.json") + " --log " + file("val.lcmlog") + " --horizons 40,80"), 0)
      << err_;
  EXPECT_NE(err_.find("leaves the measured range"), std::string::npos) << err_;
  std::istringstream table(slurp(file("stdout.txt")));
  for (std::string row; std::getline(table, row);)
    if (row.rfind("bend_deg", 0) == 0 || row.rfind("steer_deg", 0) == 0) {
      EXPECT_LT(row.size(), 60u) << row;
    }
  EXPECT_NE(slurp(file("pred.csv")).find("bend_deg_k40"), std::string::npos);
  // An output that cannot be written is an error that names it, not a silent loss.
  EXPECT_EQ(run("validate --model " + file("model.json") + " --log " + file("val.lcmlog") + " --json " +
                file("no_such_dir/fits.json")),
            1);
  EXPECT_NE(err_.find("no_such_dir/fits.json: the folder " + file("no_such_dir") + " does not exist"),
            std::string::npos)
      << err_;  // before the work, not at the write after it
  EXPECT_EQ(run("validate --model " + file("model.json") + " --log " + file("val.lcmlog") + " --json /dev/full"), 1);
  EXPECT_NE(err_.find("/dev/full: cannot write the fits file"), std::string::npos) << err_;
  // A horizon as long as the log leaves nothing to score: said in the tool's words, before any work.
  const std::string validate = "validate --model " + file("model.json") + " --log " + file("val.lcmlog");
  EXPECT_EQ(run(validate + " --horizons 40,100000"), 1);
  EXPECT_NE(err_.find("val.lcmlog: 2480 samples leave 0 to score at horizon 100000 (a fit needs 2)"), std::string::npos)
      << err_;
  EXPECT_EQ(run(validate + " --horizons 2479"), 1);
  EXPECT_NE(err_.find("leave 1 to score at horizon 2479"), std::string::npos) << err_;
  EXPECT_EQ(run(validate + " --horizons 2478"), 0) << err_;

  // '-' is standard output: the JSON alone there, the table a person reads on standard error.
  ASSERT_EQ(run(validate + " --json -"), 0) << err_;
  const auto piped = nlohmann::json::parse(slurp(file("stdout.txt")));
  EXPECT_EQ(piped["outputs"], j["outputs"]);
  EXPECT_NE(err_.find("measured std"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists("-")) << "a file named '-' was written";
  EXPECT_EQ(run(validate + " --json - --csv -"), 1);
  EXPECT_NE(err_.find("cannot both be '-'"), std::string::npos) << err_;
  // An LCM log under lcm-logger's own kind of name, on another channel: known by its content, read by --channel.
  ASSERT_EQ(
      run("simulate --experiment joystick --duration 30 --seed 2 --channel ARM_7_STATE --out " + file("other.lcmlog")),
      0)
      << err_;
  fs::rename(file("other.lcmlog"), file("lcmlog-2026-11-25.00"));
  const std::string other = "validate --model " + file("model.json") + " --log " + file("lcmlog-2026-11-25.00");
  EXPECT_EQ(run(other), 1);
  EXPECT_NE(err_.find("no actuator-state messages on channel PLSA_STATE"), std::string::npos) << err_;
  ASSERT_EQ(run(other + " --channel ARM_7_STATE --json " + file("other.json")), 0) << err_;
  EXPECT_EQ(nlohmann::json::parse(slurp(file("other.json")))["outputs"], j["outputs"]) << "the same recording";
  // A wrong command line is a usage error (2), not a failure of the tool (1).
  EXPECT_EQ(run(validate + " --no-such-option"), 2);
  EXPECT_EQ(run(validate + " --horizons forty"), 2);
  EXPECT_EQ(run(validate + " --horizons 0"), 2);
  // "nan" passes a range check (its comparisons are all false): refused by name.
  EXPECT_EQ(run("identify --log " + file("val.lcmlog") + " --fuzziness nan --out " + file("x.json")), 2);
  EXPECT_NE(err_.find("'nan' is not a finite number"), std::string::npos) << err_;
  // Its range said "Value 1.0000000001 not in range 1.000000 to 100.000000", a value inside what it printed.
  EXPECT_EQ(run("identify --log " + file("val.lcmlog") + " --fuzziness 1.0000000001 --out " + file("x.json")), 2);
  EXPECT_NE(err_.find("'1.0000000001' is not a fuzziness m over 1 (at least 1 + 1e-9) and at most 100"),
            std::string::npos)
      << err_;
  // A slow pole under the sample time failed after the structure search as "tiedSlowMode: ... (0, 1)".
  EXPECT_EQ(run("identify --log " + file("val.lcmlog") + " --slow-pole 0.001 --out " + file("x.json")), 1);
  EXPECT_NE(err_.find("identify: --slow-pole 0.001 s is shorter than the 0.0125 s sample time"), std::string::npos)
      << err_;
  EXPECT_EQ(run("identify --log " + file("val.lcmlog") + " --play-coupling 0.1,nan --out " + file("x.json")), 2);
  EXPECT_NE(err_.find("'nan' is not a finite number"), std::string::npos) << err_;
  EXPECT_EQ(run("validate --help"), 0);
  EXPECT_NE(slurp(file("stdout.txt")).find("--channel TEXT=PLSA_STATE"), std::string::npos) << "defaults in --help";
}

// The README's main job end to end: every file it names, the fits the issue
// asks for, a report that needs nothing from the network, and models that
// `plsa validate` re-scores to the demo's own figures.
// The peers the demo and generalise score plsa against, fitted on a user's
// own logs: the paper's configuration (switched PWL on the raw inputs, no
// play, the angles as logged) and the global linear OBF (one region).
TEST_F(Cli, IdentifyFitsThePapersConfigurationAndTheGlobalLinearObf) {
  ASSERT_EQ(run("simulate --experiment grid2 --seed 1 --out " + file("train.csv")), 0) << err_;
  ASSERT_EQ(run("identify --log " + file("train.csv") + " --structure paper --out " + file("paper.json")), 0) << err_;
  const plsa::DioPwlObfModel paper = plsa::loadModel(file("paper.json"));
  EXPECT_EQ(paper.partition.scheduling(), plsa::Scheduling::kSwitched);
  EXPECT_GT(paper.partition.regionCount(), 1);
  EXPECT_EQ(paper.schedule_lag_s, 0.0);
  EXPECT_EQ(paper.output_frame, plsa::OutputFrame::kAsLogged);
  for (const auto& channels : paper.shaping.play)
    for (const plsa::PlayChannel& c : channels) EXPECT_TRUE(c.passesThrough());
  // Its knobs fixed (the search that picks them has tests of its own): one
  // region whatever the search would choose.
  ASSERT_EQ(run("identify --log " + file("train.csv") +
                " --structure global-linear --play 0.12u --slow-pole 0 --play-coupling 0 --play-threshold 0 --out " +
                file("linear.json")),
            0)
      << err_;
  EXPECT_NE(err_.find("global linear OBF: the poles and play channels chosen above, one region"), std::string::npos)
      << err_;
  // By default the outputs are fitted as logged, though this simulator's
  // sensor drifts: the stage says so and names the option that estimates it.
  EXPECT_NE(err_.find("[5/5] sensor drift: not estimated (output drift off: the outputs as logged; 'auto' "
                      "(--output-drift auto) estimates"),
            std::string::npos)
      << err_;
  EXPECT_FALSE(nlohmann::json::parse(slurp(file("linear.json"))).contains("training_output_drift"));
  const plsa::DioPwlObfModel linear = plsa::loadModel(file("linear.json"));
  EXPECT_EQ(linear.partition.regionCount(), 1);
  EXPECT_EQ(linear.schedule_lag_s, 0.0);
  ASSERT_EQ(run("validate --model " + file("linear.json") + " --log " + file("train.csv")), 0) << err_;
  // A glitch in the validation log (1e160 squares to infinity: the spread was
  // inf and every fit printed 100) is refused naming its row, as identify's.
  plsa::io::Log glitched = plsa::io::readCsvLog(file("train.csv"));
  glitched.data(3000, glitched.columnIndex("bend_deg")) = 1e160;
  plsa::io::writeCsvLog(file("glitched.csv"), glitched);
  EXPECT_EQ(run("validate --model " + file("linear.json") + " --log " + file("glitched.csv")), 1);
  EXPECT_NE(err_.find("data row 3001, column 'bend_deg': 1e+160 lies"), std::string::npos) << err_;
  EXPECT_NE(err_.find("(or validate with --keep-outliers)"), std::string::npos) << err_;
  EXPECT_EQ(run("validate --model " + file("linear.json") + " --log " + file("glitched.csv") + " --keep-outliers"), 1);
  EXPECT_NE(err_.find("output 'bend_deg' reaches 1e+160 over the scored samples, beyond what a fit can be computed on"),
            std::string::npos)
      << err_;
  glitched.data(3000, glitched.columnIndex("bend_deg")) = 1e6;  // kept: scored as it is
  plsa::io::writeCsvLog(file("glitched.csv"), glitched);
  EXPECT_EQ(run("validate --model " + file("linear.json") + " --log " + file("glitched.csv")), 1);
  ASSERT_EQ(run("validate --model " + file("linear.json") + " --log " + file("glitched.csv") + " --keep-outliers"), 0)
      << err_;
  EXPECT_NE(run("identify --log " + file("train.csv") + " --structure lstm --out " + file("x.json")), 0);
  EXPECT_NE(err_.find("lstm"), std::string::npos) << err_;
  EXPECT_FALSE(std::filesystem::exists(file("x.json")));
}

// Windowed local fits on joystick data reject many fits (an hour: hundreds):
// past three for a pair, one line counts them by reason and names the first;
// --list-rejections names every one.
TEST_F(Cli, IdentifyCountsEachPairsRejectedLocalFits) {
  ASSERT_EQ(run("simulate --experiment joystick --duration 120 --seed 5 --out " + file("j.csv")), 0) << err_;
  const std::string identify = "identify --log " + file("j.csv") +
                               " --scheduling input --play 0 --slow-pole 0 --schedule-lag 0 --play-coupling 0 "
                               "--play-threshold 0 --out ";
  const auto lines = [&](const std::string& head) {
    std::size_t n = 0;
    for (std::size_t at = err_.find(head); at != std::string::npos; at = err_.find(head, at + 1)) ++n;
    return n;
  };
  ASSERT_EQ(run(identify + file("a.json")), 0) << err_;
  const std::string head = "rejected ", pair = " local fits p_1 -> bend_deg (";
  const std::size_t at = err_.find(pair);
  ASSERT_NE(at, std::string::npos) << "no count for p_1 -> bend_deg: " << err_;
  const std::size_t from = err_.rfind(head, at) + head.size();
  const int counted = std::stoi(err_.substr(from, at - from));
  EXPECT_GT(counted, 3) << err_;
  EXPECT_NE(err_.find("unstable pole", at), std::string::npos) << err_;  // a count by reason
  EXPECT_EQ(lines("rejected local fit p_1 -> bend_deg, "), 0u) << err_;
  ASSERT_EQ(run(identify + file("b.json") + " --list-rejections"), 0) << err_;
  EXPECT_EQ(lines("rejected local fit p_1 -> bend_deg, "), static_cast<std::size_t>(counted)) << err_;
  EXPECT_EQ(err_.find(pair), std::string::npos) << err_;
}

TEST_F(Cli, DemoWritesWhatItReportsAndValidateReproducesItsFits) {
  ASSERT_EQ(run("demo --out " + file("demo")), 0) << err_;
  const std::string printed = slurp(file("stdout.txt"));
  for (const std::string f : {"model.json", "fits.json", "report.html", "train_grid2.csv", "validate_joystick.csv",
                              "baseline_paper.json", "baseline_global_linear.json", "predictions.csv"}) {
    ASSERT_TRUE(fs::exists(file("demo/" + f))) << f << " missing; stdout:\n" << printed;
    EXPECT_GT(fs::file_size(file("demo/" + f)), 100u) << f;
  }
  const auto fits = nlohmann::json::parse(slurp(file("demo/fits.json")));
  const std::string plsa = "plsa", paper = "paper", global = "global_linear", arx = "arx";
  // Machine keys, with the names people read as labels.
  EXPECT_EQ(fits["models"][plsa]["label"], "DIO-PWL-OBF (plsa)");
  EXPECT_EQ(fits["models"][global]["label"], "global linear OBF (same poles, play)");
  EXPECT_EQ(fits["models"][paper]["file"], "baseline_paper.json");
  EXPECT_FALSE(fits["models"][arx].contains("file"));
  for (const std::string out : {"bend_deg", "steer_deg"}) {
    for (const std::string key : {"fit_k40", "fit_k80", "fit_sim"}) {
      ASSERT_TRUE(fits["outputs"][out].contains(key)) << out << "." << key;
      EXPECT_EQ(fits["outputs"][out][key], fits["models"][plsa][out][key]) << out << "." << key;
    }
    // The targets (90 / 90 / 85, as on the generalisation matrix) and the first baseline, on the demo's run
    // (seed 1: 89.0 to 97.4, bending's simulation the lowest; the global linear OBF 0.14 to 8.1 behind).
    // Other seeds miss some cells: docs/identification.md.
    for (const std::string key : {"fit_k40", "fit_k80", "fit_sim"}) {
      EXPECT_GE(fits["models"][plsa][out][key].get<double>(), key == "fit_sim" ? 85.0 : 90.0) << out << "." << key;
      EXPECT_GT(fits["models"][plsa][out][key].get<double>(), fits["models"][global][out][key].get<double>())
          << out << "." << key;
    }
    // The paper's configuration and ARX trail plsa's model by 9.8 points or more on seeds 1 to 8.
    for (const auto& base : {paper, arx})
      for (const std::string key : {"fit_k40", "fit_k80", "fit_sim"})
        EXPECT_GT(fits["models"][plsa][out][key].get<double>(), fits["models"][base][out][key].get<double>() + 5.0)
            << base << " " << out << "." << key;
  }
  const std::string html = slurp(file("demo/report.html"));
  EXPECT_EQ(html.rfind("<!doctype html>", 0), 0u);
  EXPECT_NE(html.find("<svg"), std::string::npos) << "no plots in the report";
  for (const std::string out : {"bend_deg", "steer_deg"})
    EXPECT_NE(html.find(out + ": residual, measured minus predicted"), std::string::npos) << out;
  // Every plotted series beside the page, linked from it: the measured run and plsa's predictions.
  EXPECT_NE(html.find("href=\"predictions.csv\""), std::string::npos);
  {
    std::ifstream csv(file("demo/predictions.csv"));
    std::string line;
    while (std::getline(csv, line) && line.rfind("#", 0) == 0) {}
    EXPECT_EQ(line,
              "time_s,bend_deg,bend_deg_k40,bend_deg_k80,bend_deg_sim,steer_deg,steer_deg_k40,steer_deg_k80,"
              "steer_deg_sim");
    const plsa::io::Log run = plsa::io::readCsvLog(file("demo/validate_joystick.csv"));
    std::size_t rows = 0;
    while (std::getline(csv, line)) ++rows;
    EXPECT_EQ(static_cast<Eigen::Index>(rows), run.samples());
  }
  for (const std::string external : {"src=\"http", "href=\"http", "<script src", "<link"})
    EXPECT_EQ(html.find(external), std::string::npos) << "the report loads " << external;
  // plsa's model and the global linear baseline, re-scored by validate with
  // the same start (yaw registered on 5 s, scored after; the training drift
  // carried, or not with --no-drift): the same simulation fits.
  using NamedFile = std::pair<std::string, std::string>;
  for (const auto& [name, model] : {NamedFile{plsa, "model.json"}, NamedFile{global, "baseline_global_linear.json"}}) {
    const double drift = nlohmann::json::parse(slurp(file("demo/" + model)))["training_output_drift"]["rate_per_s"][1];
    EXPECT_NE(drift, 0.0) << model;
    for (const std::string flag : {"", " --no-drift"}) {
      ASSERT_EQ(run("validate --model " + file("demo/" + model) + " --log " + file("demo/validate_joystick.csv") +
                    " --horizons 40,80 --json " + file("v.json") + flag),
                0)
          << model << flag << ": " << err_;
      const auto v = nlohmann::json::parse(slurp(file("v.json")));
      const std::string key = flag.empty() ? "fit_sim" : "fit_sim_no_drift";
      for (const std::string out : {"bend_deg", "steer_deg"})
        EXPECT_NEAR(v["outputs"][out]["fit_sim"].get<double>(), fits["models"][name][out][key].get<double>(), 1e-6)
            << model << flag << " " << out;
      EXPECT_EQ(v["simulation_yaw_drift_deg_per_s"].get<double>(), flag.empty() ? drift : 0.0) << model << flag;
      // The run starts from rest, and within the window the tip bends: registered on it.
      EXPECT_TRUE(v["yaw_registration"]["registered"].get<bool>()) << model << flag;
      EXPECT_GT(v["yaw_registration"]["bent_share"].get<double>(), 0.5) << model << flag;
      EXPECT_EQ(err_.find("yaw was not registered"), std::string::npos) << err_;
    }
  }
  // With a least bend no reading reaches, nothing is registered, and validate says so.
  ASSERT_EQ(run("validate --model " + file("demo/model.json") + " --log " + file("demo/validate_joystick.csv") +
                " --horizons 40 --yaw-min-bend 1000 --json " + file("v.json")),
            0)
      << err_;
  EXPECT_FALSE(nlohmann::json::parse(slurp(file("v.json")))["yaw_registration"]["registered"].get<bool>());
  EXPECT_NE(err_.find("the sensor's yaw was not registered: the tip was bent 1000 deg or more on 0% of the "
                      "registration window"),
            std::string::npos)
      << err_;
  EXPECT_NE(run("validate --model " + file("demo/model.json") + " --log " + file("demo/validate_joystick.csv") +
                " --yaw-min-bend nan"),
            0);
  // The yaw tracked past the window (default 60 s) moves the k-step
  // predictions, never the simulation; 0 holds the window's offset.
  nlohmann::json by_tracking[2];
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(run("validate --model " + file("demo/model.json") + " --log " + file("demo/validate_joystick.csv") +
                  " --horizons 40 --json " + file("v.json") + (i ? " --yaw-tracking 0" : "")),
              0)
        << err_;
    by_tracking[i] = nlohmann::json::parse(slurp(file("v.json")));
  }
  EXPECT_EQ(by_tracking[0]["yaw_registration"]["tracking_s"].get<double>(), 60.0);
  EXPECT_EQ(by_tracking[1]["yaw_registration"]["tracking_s"].get<double>(), 0.0);
  for (const std::string out : {"bend_deg", "steer_deg"}) {
    EXPECT_EQ(by_tracking[0]["outputs"][out]["fit_sim"], by_tracking[1]["outputs"][out]["fit_sim"]) << out;
    EXPECT_NE(by_tracking[0]["outputs"][out]["fit_k40"], by_tracking[1]["outputs"][out]["fit_k40"]) << out;
  }
  for (const std::string bad : {"nan", "-1", "inf"})
    EXPECT_EQ(run("validate --model " + file("demo/model.json") + " --log " + file("demo/validate_joystick.csv") +
                  " --yaw-tracking " + bad),
              2)
        << bad;
  // A memory under a sample time or beyond 1e9 s rounds to no tracking: refused, not run as none (a probe).
  for (const std::string bad : {"1e-6", "1e300"}) {
    EXPECT_EQ(run("validate --model " + file("demo/model.json") + " --log " + file("demo/validate_joystick.csv") +
                  " --yaw-tracking " + bad),
              1)
        << bad;
    EXPECT_NE(err_.find("is neither 0 (none) nor from the 0.012500 s sample time to 1e9 s"), std::string::npos) << err_;
  }
  ASSERT_EQ(run("validate --model " + file("demo/baseline_paper.json") + " --log " +
                file("demo/validate_joystick.csv") + " --horizons 40 --json " + file("v.json")),
            0)
      << err_;
  EXPECT_EQ(nlohmann::json::parse(slurp(file("demo/baseline_paper.json")))["partition"]["scheduling"], "switched");
}

// A log given twice would be trained and scored on itself (crossval) or
// weigh double (identify); a repeated horizon was averaged twice into the
// means (crossval printed fits near 200%). Each is refused by name.
TEST_F(Cli, ALogOrHorizonGivenTwiceIsRefused) {
  fs::create_directories(file("runs"));
  for (const std::string seed : {"1", "2"})
    ASSERT_EQ(
        run("simulate --experiment joystick --duration 5 --seed " + seed + " --out " + file("runs/j" + seed + ".csv")),
        0)
        << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --log " + file("runs/j1.csv")), 1);
  EXPECT_NE(err_.find("crossval: " + file("runs/j1.csv") + " is given twice"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("runs/j1.csv") + " --log " + file("runs/../runs/j1.csv") + " --out " +
                file("m.json")),
            1);
  EXPECT_NE(err_.find("is given twice (also as " + file("runs/j1.csv") + ")"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(file("m.json")));
  fs::copy_file(file("runs/j1.csv"), file("runs/j1_copy.csv"));
  EXPECT_EQ(run("crossval --log " + file("runs")), 1);
  EXPECT_NE(err_.find("crossval: " + file("runs/j1_copy.csv") + " holds the same samples as " + file("runs/j1.csv")),
            std::string::npos)
      << err_;
  fs::remove(file("runs/j1_copy.csv"));
  // A file of the folder that is not a log is named, not passed over in silence.
  std::ofstream(file("runs/notes.txt")) << "trial 3 was cut short\n";
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 1,12,1"), 1);
  EXPECT_NE(err_.find("crossval: note: " + file("runs") + ": 1 file not read, not being logs (.csv"), std::string::npos)
      << err_;
  EXPECT_NE(err_.find("by content): notes.txt"), std::string::npos) << err_;
  EXPECT_NE(err_.find("crossval: horizon 1 is given twice"), std::string::npos) << err_;
  std::string many = "1";  // each horizon costs a prediction per sample: 4000 took validate 2.1 GB
  for (int k = 2; k <= 33; ++k) many += "," + std::to_string(k);
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons " + many), 1);
  EXPECT_NE(err_.find("crossval: 33 horizons given; at most 32"), std::string::npos) << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 1,477"), 1);
  EXPECT_NE(err_.find("j1.csv: 480 samples are too few to score horizon 477 after ARX's 4 lags"), std::string::npos)
      << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 0"), 2);  // a usage error
  EXPECT_NE(err_.find("--horizons"), std::string::npos) << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --output-drift sometimes"), 2);  // identify's choices
  EXPECT_NE(err_.find("--output-drift"), std::string::npos) << err_;
  fs::create_directories(file("empty"));
  EXPECT_EQ(run("crossval --log " + file("empty") + " --log " + file("runs")), 1);
  EXPECT_NE(err_.find("empty: no logs in this folder (.csv, .lcmlog, .candump, LCM event logs by content, or candump "
                      "bus logs by content)"),
            std::string::npos)
      << err_;
}

TEST_F(Cli, BadInputGetsAClearErrorNotACrash) {
  // A full disk is an error that names the file, for logs and for whole-text outputs.
  if (fs::exists("/dev/full")) {
    EXPECT_EQ(run("simulate --experiment joystick --duration 1 --seed 1 --out /dev/full"), 1);
    EXPECT_NE(err_.find("/dev/full: cannot write the log: No space left on device"), std::string::npos) << err_;
    EXPECT_EQ(run("sim-config --out /dev/full"), 1);
    EXPECT_NE(err_.find("/dev/full: cannot write the simulator configuration"), std::string::npos) << err_;
  }
  std::ofstream(file("bad.csv")) << "time_s,p_1\n0,0.1\n0.0125,oops\n";
  EXPECT_EQ(run("identify --log " + file("bad.csv") + " --inputs p_1 --outputs p_1 --out " + file("m.json")), 1);
  EXPECT_NE(err_.find("bad.csv:3: column 'p_1': 'oops' is not a number"), std::string::npos) << err_;
  std::ofstream(file("ok.csv")) << "time_s,u\n0,0.1\n0.0125,0.2\n";
  EXPECT_EQ(run("identify --log " + file("ok.csv") + " --out " + file("m.json")), 1);
  EXPECT_NE(err_.find("no column 'p_1'"), std::string::npos) << err_;
  std::ofstream(file("model.json")) << "{\"schema\": \"plsa.dio_pwl_obf\", \"version\": 1}";
  EXPECT_EQ(run("validate --model " + file("model.json") + " --log " + file("ok.csv")), 1);
  EXPECT_NE(err_.find("missing field 'sample_time_s'"), std::string::npos) << err_;
  EXPECT_NE(run("simulate --experiment sine --out " + file("x.csv")), 0);
  // Number options name the value and the bound in one short line.
  for (const std::string bad : {"inf", "-1", "1e400", "abc"}) {
    EXPECT_NE(run("simulate --experiment joystick --duration " + bad + " --out " + file("x.csv")), 0) << bad;
    EXPECT_NE(err_.find("--duration: '" + bad + "' is not a finite number above 0\n"), std::string::npos) << err_;
    EXPECT_LT(err_.size(), 200u) << err_;
  }
  // A seed is digits: CLI11 read -3 as 2^64 - 3 and clamped an overlong one, each another run.
  for (const std::string bad : {"-3", "18446744073709551616", "99999999999999999999999", "1.5", "0x10"}) {
    EXPECT_NE(run("simulate --experiment joystick --duration 1 --seed " + bad + " --out " + file("x.csv")), 0) << bad;
    EXPECT_NE(err_.find("--seed: '" + bad + "' is not a seed (a whole number from 0 to 18446744073709551615)"),
              std::string::npos)
        << err_;
  }
  for (const std::string& cmd :
       std::vector<std::string>{"demo --seed -1 --out " + file("d"), "sim --seed -1", "diagnose-selfcheck --seed -1"}) {
    EXPECT_NE(run(cmd), 0) << cmd;
    EXPECT_NE(err_.find("--seed: '-1' is not a seed"), std::string::npos) << cmd << ": " << err_;
  }
  ASSERT_EQ(run("simulate --experiment joystick --duration 1 --seed 18446744073709551615 --out " + file("x.csv")), 0)
      << err_;
  EXPECT_NE(err_.find("seed 18446744073709551615\n"), std::string::npos) << err_;
  // A mistyped duration is refused by its size, not by bad_alloc.
  EXPECT_EQ(run("simulate --experiment joystick --duration 1e9 --out " + file("x.csv")), 1);
  EXPECT_NE(err_.find("joystick: 1e+09 s at 80 Hz is 8e+10 samples, above the 10000000 one experiment holds "
                      "(34.7 h at this rate); split it into several runs"),
            std::string::npos)
      << err_;
  EXPECT_EQ(run("simulate --experiment grid2 --duration 1e6 --out " + file("x.csv")), 1);
  EXPECT_NE(err_.find("grid2: "), std::string::npos) << err_;
  EXPECT_NE(err_.find("split it into several runs"), std::string::npos) << err_;
  EXPECT_NE(run("sim --duration -2"), 0);
  EXPECT_NE(err_.find("--duration: '-2' is not a finite number at least 0\n"), std::string::npos) << err_;
  std::ofstream(file("steps.csv")) << "time_s,p_1,bend_deg\n0,0.1,1\n0.0125,0.2,2\n";
  EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --play 0.1,abc --out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("'abc' is not a width (e.g. 0.1) or a slope (e.g. 0.12u)"), std::string::npos) << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --play -0.1u --out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("'-0.1u' is not a width"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --play 1e308u --out " +
                file("m.json")),
            2);  // a band wider than the input's range never moves
  EXPECT_NE(err_.find("'1e308u' is not a width (e.g. 0.1) or a slope (e.g. 0.12u) of at most 1"), std::string::npos)
      << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --play-bank 0/0.1,0.2 --out " + file("m.json")),
            2);  // a bank of one play is a --play set
  EXPECT_NE(err_.find("--play-bank: '0.2' is one play; a bank has two or more (0/0.07/0.2)"), std::string::npos)
      << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --play-bank 0/x --out " +
                file("m.json")),
            2);
  EXPECT_NE(err_.find("--play-bank: 'x' is not a width"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --play-bank-min-gain -1 --out " + file("m.json")),
            2);
  EXPECT_NE(err_.find("--play-bank-min-gain: '-1' is not a finite number at least 0"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --play-bank-min-gain inf --out " + file("m.json")),
            2);
  EXPECT_NE(err_.find("--play-bank-min-gain: 'inf' is not a finite number at least 0"), std::string::npos) << err_;
  EXPECT_EQ(run("crossval --log " + file("steps.csv") + " --log " + file("steps.csv") + " --play-bank 0.2"),
            2);  // crossval's banks are identify's, refused alike
  EXPECT_NE(err_.find("--play-bank: '0.2' is one play; a bank has two or more (0/0.07/0.2)"), std::string::npos)
      << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --schedule-lag 0.4,-1 --out " + file("m.json")),
            0);
  EXPECT_NE(err_.find("'-1' is not a time constant in seconds"), std::string::npos) << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --slow-pole 5,slow --out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("'slow' is not a time constant in seconds up to a day (e.g. 5)"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --slow-pole-form loose --out " + file("m.json")),
            2);
  EXPECT_NE(err_.find("--slow-pole-form: loose not in {tied,free}"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --slow-pole-count 3 --out " +
                file("m.json")),
            2);
  EXPECT_NE(err_.find("--slow-pole-count: Value 3 not in range 1 to 2"), std::string::npos) << err_;
  // A pole of 1e300 s is 1 to rounding: refused as an option, not after the whole identification.
  EXPECT_EQ(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --slow-pole 1e300 --out " +
                file("m.json")),
            2);
  EXPECT_NE(err_.find("'1e300' is not a time constant in seconds up to a day"), std::string::npos) << err_;
  // The bound in a few digits (CLI11's own check printed the largest double's 309).
  EXPECT_EQ(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --search-samples -1 --out " +
                file("m.json")),
            2);
  EXPECT_NE(err_.find("'-1' is not a finite number at least 0"), std::string::npos) << err_;
  EXPECT_LT(err_.size(), 300u) << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --output-frame tip_cartesian "
                "--out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("tip_cartesian output frame needs exactly two outputs"), std::string::npos) << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --output-frame polar --out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("--output-frame"), std::string::npos) << err_;
  for (const std::string bad :
       {"--play-threshold 1.5", "--play-threshold low", "--play-coupling -0.2", "--output-drift sometimes",
        "--refine-play -1", "--refine-play 20000", "--play-softening 0.5"}) {
    EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg " + bad + " --out " +
                  file("m.json")),
              0)
        << bad;
    EXPECT_NE(err_.find(bad.substr(0, bad.find(' '))), std::string::npos) << bad << ": " << err_;
  }
}
