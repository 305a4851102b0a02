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
                "--play-threshold 0.2 --out " +
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
  EXPECT_EQ(drift.find("bend_deg "), std::string::npos) << drift;
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
  EXPECT_NE(slurp(file("pred.csv")).find("bend_deg_k40"), std::string::npos);
  // An output that cannot be written is an error that names it, not a silent loss.
  EXPECT_EQ(run("validate --model " + file("model.json") + " --log " + file("val.lcmlog") + " --json " +
                file("no_such_dir/fits.json")),
            1);
  EXPECT_NE(err_.find("no_such_dir/fits.json: cannot write the fits file"), std::string::npos) << err_;
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
  ASSERT_EQ(run("identify --log " + file("train.csv") + " --structure global-linear --out " + file("linear.json")), 0)
      << err_;
  const plsa::DioPwlObfModel linear = plsa::loadModel(file("linear.json"));
  EXPECT_EQ(linear.partition.regionCount(), 1);
  EXPECT_EQ(linear.schedule_lag_s, 0.0);
  ASSERT_EQ(run("validate --model " + file("linear.json") + " --log " + file("train.csv")), 0) << err_;
  EXPECT_NE(run("identify --log " + file("train.csv") + " --structure lstm --out " + file("x.json")), 0);
  EXPECT_NE(err_.find("lstm"), std::string::npos) << err_;
  EXPECT_FALSE(std::filesystem::exists(file("x.json")));
}

TEST_F(Cli, DemoWritesWhatItReportsAndValidateReproducesItsFits) {
  ASSERT_EQ(run("demo --out " + file("demo")), 0) << err_;
  const std::string printed = slurp(file("stdout.txt"));
  for (const std::string f : {"model.json", "fits.json", "report.html", "train_grid2.csv", "validate_joystick.csv",
                              "baseline_paper.json", "baseline_global_linear.json"}) {
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
    // The issue's floor and its first baseline, on the demo's run (seed 1: 92.2 to 97.3; the global linear
    // OBF 0.05 to 10.3 behind). Other seeds miss some cells: docs/identification.md.
    for (const std::string key : {"fit_k40", "fit_k80", "fit_sim"}) {
      EXPECT_GE(fits["models"][plsa][out][key].get<double>(), 90.0) << out << "." << key;
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
    }
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
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 1,12,1"), 1);
  EXPECT_NE(err_.find("crossval: horizon 1 is given twice"), std::string::npos) << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 1,477"), 1);
  EXPECT_NE(err_.find("j1.csv: 480 samples are too few to score horizon 477 after ARX's 4 lags"), std::string::npos)
      << err_;
  EXPECT_EQ(run("crossval --log " + file("runs") + " --horizons 0"), 1);
  EXPECT_NE(err_.find("crossval: horizons must be >= 1, got 0"), std::string::npos) << err_;
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
  EXPECT_NE(run("identify --log " + file("steps.csv") +
                " --inputs p_1 --outputs bend_deg --schedule-lag 0.4,-1 --out " + file("m.json")),
            0);
  EXPECT_NE(err_.find("'-1' is not a time constant in seconds"), std::string::npos) << err_;
  EXPECT_NE(run("identify --log " + file("steps.csv") + " --inputs p_1 --outputs bend_deg --slow-pole 5,slow --out " +
                file("m.json")),
            0);
  EXPECT_NE(err_.find("'slow' is not a time constant in seconds (e.g. 5)"), std::string::npos) << err_;
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

TEST_F(Cli, DiagnoseRunsOnLogsAndRejectsBadOnes) {
  // Data from an actuator with hysteresis; a simulator with every effect off,
  // asked about two candidates.
  ASSERT_EQ(run("sim-config --out " + file("full.json")), 0) << err_;
  auto j = nlohmann::json::parse(slurp(file("full.json")));
  for (const char* e : {"deadzone", "stiffening", "coupling", "pneumatic_lag", "creep", "sensor_bias"})
    j[e]["enabled"] = false;
  std::ofstream(file("truth.json")) << j.dump();
  j["hysteresis"]["enabled"] = false;
  std::ofstream(file("sim.json")) << j.dump();
  ASSERT_EQ(run("simulate --config " + file("truth.json") + " --experiment staircase1 --seed 3 --out " + file("a.csv")),
            0)
      << err_;
  ASSERT_EQ(run("simulate --config " + file("truth.json") + " --experiment joystick --duration 30 --seed 4 --out " +
                file("b.csv")),
            0)
      << err_;
  ASSERT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("a.csv") + " --real " + file("b.csv") +
                " --candidates hysteresis,creep --evaluations 60 --out " + file("diag")),
            0)
      << err_;
  const auto d = nlohmann::json::parse(slurp(file("diag/diagnosis.json")));
  ASSERT_EQ(d["ranking"].size(), 2u);
  EXPECT_EQ(d["ranking"][0]["effect"], "hysteresis");
  EXPECT_TRUE(fs::exists(file("diag/report.html")));
  EXPECT_TRUE(fs::exists(file("diag/calibrated_sim.json")));
  EXPECT_NE(err_.find("nominal calibration"), std::string::npos) << "no progress shown: " << err_;
  // Bad input: a command column far outside the simulator's range names the fix.
  std::ofstream(file("psi.csv")) << "time_s,cmd_1,cmd_2,cmd_3,bend_deg,steer_deg\n";
  {
    std::ofstream f(file("psi.csv"), std::ios::app);
    for (int i = 0; i < 100; ++i) f << 0.0125 * i << ",5,0,0,1,0\n";
  }
  EXPECT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("psi.csv") + " --out " + file("d2")), 1);
  EXPECT_NE(err_.find("check --input-scale"), std::string::npos) << err_;
  // One run twice would be both trained and held out on.
  EXPECT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("a.csv") + " --real " + file("b.csv") +
                " --real " + file("a.csv") + " --out " + file("d3")),
            1);
  EXPECT_NE(err_.find("diagnose: " + file("a.csv") + " is given twice"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(file("d3")));
}

TEST_F(Cli, DiagnoseSelfcheckMeetsItsTargetsOnASmallSet) {
  // Hysteresis withheld as the play operator and as Prandtl-Ishlinskii, with
  // perturbed nominal physics, and a null case; the full set is in docs/diagnosis.md.
  ASSERT_EQ(run("diagnose-selfcheck --truth own --settled --effects hysteresis --seeds 2 --no-pairs --null 1 "
                "--train-s 40 --heldout-s 30 "
                "--out " +
                file("sc.json")),
            0)
      << err_ << slurp(file("stdout.txt"));
  const auto j = nlohmann::json::parse(slurp(file("sc.json")));
  ASSERT_EQ(j["cases"].size(), 3u);
  EXPECT_TRUE(j["targets_met"].get<bool>());
  EXPECT_EQ(j["cases"][1]["formulation"], "hysteresis prandtl_ishlinskii");
  EXPECT_TRUE(j["cases"][2]["selected"].empty()) << "the null case claimed an effect";
  EXPECT_NE(slurp(file("stdout.txt")).find("confusion matrix"), std::string::npos);
}

TEST_F(Cli, IndependentSelfcheckCasesAreSavedForDiagnoseAndScored) {
  // The default truth: an independently written actuator, recorded from rest.
  // A withheld deadzone (logistic law) and a null case; the whole 40-case
  // matrix is in docs/diagnosis.md. Its runs go to CSV and diagnose reads them.
  fs::create_directories(file("runs"));
  // Exit 1 when a target is missed (here, on two cases, the shrink target
  // may be), after the results are written.
  const int rc =
      run("diagnose-selfcheck --effects deadzone --seeds 1 --no-pairs --null 1 --train-s 40 --heldout-s 30 "
          "--save-runs " +
          file("runs") + " --out " + file("sc.json"));
  ASSERT_TRUE(rc == 0 || rc == 1) << err_;
  const auto j = nlohmann::json::parse(slurp(file("sc.json")));
  EXPECT_EQ(rc == 0, j["targets_met"].get<bool>());
  EXPECT_NE(slurp(file("stdout.txt")).find("confusion matrix"), std::string::npos);
  EXPECT_EQ(j["truth"], "independent");
  ASSERT_EQ(j["cases"].size(), 2u);
  EXPECT_EQ(j["cases"][0]["formulation"], "deadzone logistic");
  EXPECT_EQ(j["cases"][0]["selected"][0], "deadzone");
  EXPECT_GT(j["cases"][0]["effect_size_percent"].get<double>(), 1.0);
  EXPECT_EQ(j["cases"][1]["effect_size_percent"].get<double>(), 0.0);
  EXPECT_TRUE(j["summary"].contains("gap_single_cases"));
  const std::string train = file("runs") + "/deadzone__logistic___1_train.csv";
  const std::string held = file("runs") + "/deadzone__logistic___1_heldout.csv";
  ASSERT_TRUE(fs::exists(train) && fs::exists(held));
  ASSERT_EQ(run("sim-config --out " + file("sim.json")), 0);
  auto sim = nlohmann::json::parse(slurp(file("sim.json")));
  for (const char* e : {"deadzone", "hysteresis", "stiffening", "coupling", "pneumatic_lag", "creep", "sensor_bias"})
    sim[e]["enabled"] = false;
  std::ofstream(file("off.json")) << sim.dump();
  ASSERT_EQ(run("diagnose --sim " + file("off.json") + " --real " + train + " " + held +
                " --candidates deadzone creep --out " + file("dg")),
            0)
      << err_;
  const auto d = nlohmann::json::parse(slurp(file("dg") + "/diagnosis.json"));
  EXPECT_EQ(d["selected"][0], "deadzone");
  // The runs were recorded from rest and are replayed so: the gap the self-check saw (up to the
  // optimiser's path, which rounding in the CSV moves; a case misread as settled gave 18.1% for 11.3%).
  const double seen = j["cases"][0]["gap_before"].get<double>();
  EXPECT_NEAR(d["gap_before"].get<double>(), seen, 0.05 * seen);
  for (const char* f : {"trace.csv", "gap_map.csv", "shrink.csv"}) EXPECT_TRUE(fs::exists(file("dg") + "/" + f)) << f;
}

TEST_F(Cli, CanBridgeRefusesOptionsTheBusCannotCarryBeforeOpeningIt) {
  // memq:// keeps LCM in-process should a check ever let the bridge run.
  const std::string base = "can-bridge --iface udp:7390:7391 --url memq:// --duration 0.2 ";
  EXPECT_EQ(run(base + "--max-pressure 5"), 1);
  EXPECT_NE(err_.find("signal 'setpoint_1' carries 0 to 0.65535 bar; the vent (0) and the set-point clamp (5 bar)"),
            std::string::npos)
      << err_;
  EXPECT_EQ(err_.find("clamp 5.000 bar"), std::string::npos) << "the bridge started: " << err_;
  for (const std::string rate : {"1e6", "0", "-3", "nan"}) {
    EXPECT_EQ(run(base + "--rate " + rate), 1) << rate;
    EXPECT_NE(err_.find("--rate"), std::string::npos) << rate << ": " << err_;
    EXPECT_NE(err_.find("is outside (0, 1000] Hz"), std::string::npos) << rate << ": " << err_;
  }
  // The watchdogs act at ticks: fewer than two per timeout would stretch it.
  EXPECT_EQ(run(base + "--rate 5"), 1);
  EXPECT_NE(err_.find("--rate 5 Hz ticks every 0.2 s, but the --sensor-timeout of 0.1 s needs a tick at least every "
                      "0.05 s (--rate 20 or more)"),
            std::string::npos)
      << err_;
  EXPECT_EQ(run(base + "--rate 5 --sensor-timeout 1 --command-timeout 0.3"), 1);
  EXPECT_NE(err_.find("the --command-timeout of 0.3 s"), std::string::npos) << err_;
  EXPECT_EQ(run(base + "--rate 5 --sensor-timeout 0.4 --command-timeout 0.4"), 0) << err_;
  // The same clamp on a profile with 1e-4 bar counts (0 to 6.5535 bar) is accepted and the bridge runs.
  std::ofstream(file("wide.json")) << R"({"profile": "wide", "messages": [
    {"name": "valve_command", "id": 256, "dlc": 8, "counter_byte": 6, "checksum_byte": 7, "signals": [
      {"name": "s1", "byte": 0, "bits": 16, "endian": "little", "scale": 1e-4},
      {"name": "s2", "byte": 2, "bits": 16, "endian": "little", "scale": 1e-4},
      {"name": "s3", "byte": 4, "bits": 16, "endian": "little", "scale": 1e-4}]},
    {"name": "pressure_sensor", "id": 512, "dlc": 8, "counter_byte": 6, "checksum_byte": 7, "signals": [
      {"name": "p1", "byte": 0, "bits": 16, "endian": "little", "scale": 1e-4},
      {"name": "p2", "byte": 2, "bits": 16, "endian": "little", "scale": 1e-4},
      {"name": "p3", "byte": 4, "bits": 16, "endian": "little", "scale": 1e-4}]}]})";
  EXPECT_EQ(run(base + "--max-pressure 5 --profile " + file("wide.json")), 0) << err_;
  EXPECT_NE(err_.find("(profile wide)"), std::string::npos) << err_;
  EXPECT_NE(err_.find("clamp 5.000 bar"), std::string::npos) << err_;
}

namespace {

// A small valid model of p_1, p_2 -> bend_deg (schema version 2), as text.
std::string smallModelJson(double first_coefficient) {
  nlohmann::json j = nlohmann::json::parse(R"({"schema": "plsa.dio_pwl_obf", "version": 2, "sample_time_s": 0.0125,
    "inputs": ["p_1", "p_2"], "outputs": ["bend_deg"], "units": {"inputs": "bar", "outputs": "deg"},
    "input_range": [0.0, 0.4], "poles": [[[[0.5, 0.0], [0.8, 0.0]], [[0.6, 0.1], [0.6, -0.1]]]],
    "input_play": [[0.0], [0.0]], "play_start": "rising", "play_coupling": 0.0, "play_threshold": 0.0,
    "play_softening": 0.0, "schedule_lag_s": 0.0, "schedule_side": "output", "output_frame": "as_logged",
    "partition": {"inputs": [], "scheduling": "switched", "breakpoints": [], "direction_split": false,
                  "direction_threshold": 0.001},
    "regions": [{"samples": 100, "fallback_from": -1, "note": "", "coefficients": [[0.1, 0.2, 0.3, 0.4]]}]})");
  j["regions"][0]["coefficients"][0][0] = first_coefficient;
  return j.dump(1);
}

}  // namespace

// Files a careless user or an attacker hands the tools: each ends in an error
// that names the file and the reason, and no output replaces an input.
TEST_F(Cli, HostileFilesAndOverwritesEndInNamedErrors) {
  ASSERT_EQ(run("simulate --experiment joystick --duration 20 --seed 2 --out " + file("j.csv")), 0) << err_;
  std::ofstream(file("m.json")) << smallModelJson(0.1);
  ASSERT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --horizons 40"), 0) << err_;
  const std::string log_before = slurp(file("j.csv")), model_before = slurp(file("m.json"));

  // Zero samples once ended in SIGSEGV.
  EXPECT_EQ(run("simulate --experiment joystick --duration 0.006 --out " + file("x.csv")), 1);
  EXPECT_NE(err_.find("joystick: a duration of 0.006 s is under two samples at 80 Hz"), std::string::npos) << err_;
  // An endless file as a model grew without bound.
  EXPECT_EQ(run("validate --model /dev/zero --log " + file("j.csv")), 1);
  EXPECT_NE(err_.find("/dev/zero: the model file is larger than 64 MiB"), std::string::npos) << err_;

  // Outputs never replace inputs: the training log, the model, the validation log.
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --out " + file("j.csv")), 1);
  EXPECT_NE(err_.find("--out " + file("j.csv") + " is an input"), std::string::npos) << err_;
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --json " + file("m.json")), 1);
  EXPECT_NE(err_.find("plsa never writes over what it reads"), std::string::npos) << err_;
  fs::create_symlink(file("j.csv"), file("link.csv"));
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --csv " + file("link.csv")), 1);
  EXPECT_NE(err_.find("is the input " + file("j.csv")), std::string::npos) << err_;
  EXPECT_EQ(run("simulate --config " + file("m.json") + " --experiment joystick --out " + file("m.json")), 1);
  EXPECT_EQ(slurp(file("j.csv")), log_before);
  EXPECT_EQ(slurp(file("m.json")), model_before);

  // Validation needs the time column: without it no rate or gap could be checked.
  {
    std::ifstream in(file("j.csv"));
    std::ofstream out(file("untimed.csv"));
    for (std::string line; std::getline(in, line);) {
      if (line[0] == '#') continue;
      out << line.substr(line.find(',') + 1) << "\n";
    }
  }
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("untimed.csv")), 1);
  EXPECT_NE(err_.find("untimed.csv:1: header has no column 'time_s'"), std::string::npos) << err_;

  // A score that is no number is an error, not a table of -inf.
  std::ofstream(file("huge.json")) << smallModelJson(1e300);
  EXPECT_EQ(run("validate --model " + file("huge.json") + " --log " + file("j.csv") + " --horizons 40"), 1);
  EXPECT_NE(err_.find("is -inf: the model's predictions reach"), std::string::npos) << err_;

  // One glitch of 1e6 deg in the training data: refused by row and column.
  {
    std::ifstream in(file("j.csv"));
    std::ofstream out(file("spike.csv"));
    int data_row = 0;
    for (std::string line; std::getline(in, line);) {
      if (line[0] != '#' && line[0] != 't' && ++data_row == 500)
        line = line.substr(0, line.rfind(',', line.rfind(',') - 1)) + ",1e6," + line.substr(line.rfind(',') + 1);
      out << line << "\n";
    }
  }
  EXPECT_EQ(run("identify --log " + file("spike.csv") + " --out " + file("spike.json")), 1);
  EXPECT_NE(err_.find("spike.csv: data row 500, column 'bend_deg': 1e+06 lies"), std::string::npos) << err_;
  EXPECT_NE(err_.find("--keep-outliers"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(file("spike.json")));

  // lcm-logger's own file names have no extension: the magic number tells.
  ASSERT_EQ(run("simulate --experiment joystick --duration 20 --seed 2 --out " + file("j.lcmlog")), 0) << err_;
  fs::rename(file("j.lcmlog"), file("lcmlog-2026-11-25.00"));
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("lcmlog-2026-11-25.00") + " --horizons 40"), 0)
      << err_;
}

// A bus recording as users make one (candump -l) feeds the tools like any
// log: a simulated run written as CAN frames, read back to the signals'
// resolution, and validated on directly; a log the bus could not carry and
// an unknown profile are named.
TEST_F(Cli, CandumpBusLogsConvertBothWaysAndFeedValidate) {
  ASSERT_EQ(run("simulate --experiment joystick --duration 20 --seed 2 --out " + file("j.csv")), 0) << err_;
  ASSERT_EQ(run("convert --in " + file("j.csv") + " --out " + file("j.candump")), 0) << err_;
  const std::string bus = slurp(file("j.candump"));
  ASSERT_EQ(bus.find("(40.012500) can0 200#"), 0u) << bus.substr(0, 200);  // the run's own times
  // By content, under candump's own file name.
  fs::copy_file(file("j.candump"), file("candump-2026-11-26_120000.log"));
  ASSERT_EQ(run("convert --in " + file("candump-2026-11-26_120000.log") + " --out " + file("back.csv")), 0) << err_;
  const plsa::io::Log before = plsa::io::readCsvLog(file("j.csv")), after = plsa::io::readCsvLog(file("back.csv"));
  ASSERT_EQ(after.samples(), before.samples());
  for (const char* c : {"p_1", "p_2", "p_3", "cmd_1", "cmd_3"})
    EXPECT_LT((after.column(c) - before.column(c)).cwiseAbs().maxCoeff(), 0.6e-5) << c;  // 1e-5 bar per count
  for (const char* c : {"bend_deg", "steer_deg"})
    EXPECT_LT((after.column(c) - before.column(c)).cwiseAbs().maxCoeff(), 0.6e-2) << c;  // 0.01 deg per count
  std::ofstream(file("m.json")) << smallModelJson(0.1);
  ASSERT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.candump") + " --horizons 40 --json " +
                file("fits.json")),
            0)
      << err_;
  EXPECT_TRUE(nlohmann::json::parse(slurp(file("fits.json"))).dump().find("bend_deg") != std::string::npos);
  // A pressure beyond what the 16-bit signal carries (0.65535 bar) is named, not wrapped.
  {
    std::string text = slurp(file("j.csv"));
    const auto row = text.find('\n', text.find("\ntime_s,") + 1) + 1;  // the first row after the header
    const auto p1 = text.find(',', text.find(',', text.find(',', text.find(',', row) + 1) + 1) + 1) + 1;
    text.replace(p1, text.find(',', p1) - p1, "0.9");
    std::ofstream(file("high.csv")) << text;
  }
  EXPECT_EQ(run("convert --in " + file("high.csv") + " --out " + file("high.candump")), 1);
  EXPECT_NE(err_.find("row 1 of " + file("high.csv") + ": pressure_sensor cannot carry its values"), std::string::npos)
      << err_;
  EXPECT_FALSE(fs::exists(file("high.candump")));
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.candump") + " --can-profile " +
                file("nothing.json")),
            2);
}

// CAN profiles as the bus's own DBC file: plsa's written as DBC, read back
// (as JSON it is the documented profile file), and taken by --can-profile.
TEST_F(Cli, CanProfilesGoBetweenJsonAndDbc) {
  ASSERT_EQ(run("can-profile --out " + file("plsa.dbc")), 0) << err_;
  EXPECT_NE(slurp(file("plsa.dbc")).find("BO_ 512 pressure_sensor: 8 plsa"), std::string::npos);
  ASSERT_EQ(run("can-profile --in " + file("plsa.dbc") + " --out " + file("back.json")), 0) << err_;
  std::string documented = slurp(std::string(PLSA_SOURCE_DIR) + "/docs/can-default-profile.json");
  documented.replace(documented.find("plsa-default"), 12, "plsa");  // a DBC's profile is its file's name
  EXPECT_EQ(slurp(file("back.json")), documented);
  ASSERT_EQ(run("simulate --experiment joystick --duration 5 --seed 2 --out " + file("j.csv")), 0) << err_;
  ASSERT_EQ(run("convert --in " + file("j.csv") + " --out " + file("j.candump") + " --can-profile " + file("plsa.dbc")),
            0)
      << err_;
  ASSERT_EQ(
      run("convert --in " + file("j.candump") + " --out " + file("j2.csv") + " --can-profile " + file("plsa.dbc")), 0)
      << err_;
  std::ofstream(file("bad.dbc")) << "BO_ 512 pressure_sensor: 8 A\n SG_ p : 3|16@1+ (1,0) [0|0] \"\" A\n";
  EXPECT_EQ(run("convert --in " + file("j.candump") + " --out " + file("j3.csv") + " --can-profile " + file("bad.dbc")),
            1);
  EXPECT_NE(err_.find("bad.dbc:2: message 'pressure_sensor', signal 'p': starts at bit 3"), std::string::npos) << err_;
  EXPECT_EQ(run("can-profile --in " + file("plsa.dbc") + " --out " + file("plsa.dbc")), 1);  // never over an input
}
