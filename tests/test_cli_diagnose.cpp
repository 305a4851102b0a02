// plsa diagnose and diagnose-selfcheck as a user runs them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>
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

namespace {
// Data from an actuator with hysteresis (a.csv, b.csv) and a simulator with
// every effect off (sim.json), written into the test's directory.
class DiagnoseOnLogs : public plsa::test::CliTest {
 protected:
  void SetUp() override {
    CliTest::SetUp();
    writeHysteresisCase();
  }
  void writeHysteresisCase();
};

void DiagnoseOnLogs::writeHysteresisCase() {
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
}
}  // namespace

// Asked about two candidates, diagnose ranks the withheld one first and writes its report.
TEST_F(DiagnoseOnLogs, RanksTheWithheldEffectFirst) {
  ASSERT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("a.csv") + " --real " + file("b.csv") +
                " --candidates hysteresis,creep --evaluations 60 --out " + file("diag")),
            0)
      << err_;
  const auto d = nlohmann::json::parse(slurp(file("diag/diagnosis.json")));
  EXPECT_TRUE(d["identified_reference"]["available"].get<bool>()) << d["identified_reference"].dump();
  ASSERT_EQ(d["ranking"].size(), 2u);
  EXPECT_EQ(d["ranking"][0]["effect"], "hysteresis");
  EXPECT_TRUE(fs::exists(file("diag/report.html")));
  EXPECT_TRUE(fs::exists(file("diag/calibrated_sim.json")));
  EXPECT_NE(err_.find("nominal calibration"), std::string::npos) << "no progress shown: " << err_;
}

TEST_F(DiagnoseOnLogs, RejectsBadOnes) {
  // A command column far outside the simulator's range names the fix.
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
  // Pressure columns named on the command line must be there (a typo ran without pressures, silently).
  EXPECT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("a.csv") + " --real " + file("b.csv") +
                " --pressures pa,pb,pc --out " + file("d4")),
            1);
  EXPECT_NE(err_.find("'pa'"), std::string::npos) << err_;
  // A log stamped every 2 s is named, not the simulator's configuration.
  std::ofstream(file("slow.csv")) << "time_s,cmd_1,cmd_2,cmd_3,bend_deg,steer_deg\n";
  {
    std::ofstream f(file("slow.csv"), std::ios::app);
    for (int i = 0; i < 100; ++i) f << 2.0 * i << "," << (i % 10 < 5 ? 0.1 : 0.3) << ",0,0," << i % 7 << ",0\n";
  }
  EXPECT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("slow.csv") + " --out " + file("d5")), 1);
  EXPECT_NE(err_.find(file("slow.csv") + "': its time column steps every 2 s (0.5 Hz)"), std::string::npos) << err_;
}

// A log without the default pressure columns is diagnosed on its outputs, and a note says so.
TEST_F(DiagnoseOnLogs, NotesALogWithoutPressures) {
  for (const char* name : {"a", "b"}) {
    std::ifstream in(file(std::string(name) + ".csv"));
    std::ofstream out(file(std::string(name) + "_nop.csv"));
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<std::string> f;
      std::stringstream ss(line);
      for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
      ASSERT_EQ(f.size(), 9u) << line;  // time, 3 commands, 3 pressures, 2 angles
      out << f[0] << ',' << f[1] << ',' << f[2] << ',' << f[3] << ',' << f[7] << ',' << f[8] << '\n';
    }
  }
  ASSERT_EQ(run("diagnose --sim " + file("sim.json") + " --real " + file("a_nop.csv") + " --real " + file("b_nop.csv") +
                " --candidates hysteresis --evaluations 20 --evaluations-per-parameter 0 --screen-evaluations 0 "
                "--no-identified-reference --out " +
                file("d6")),
            0)
      << err_;
  EXPECT_NE(err_.find("note: " + file("a_nop.csv") + " has no pressure columns"), std::string::npos) << err_;
  const auto d = nlohmann::json::parse(slurp(file("d6/diagnosis.json")));
  EXPECT_EQ(d["gap_before_detail"]["pressures"].get<double>(), 0.0);
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

TEST_F(Cli, SelfcheckCountsPairsByTheirRankingAndByWhatWasSelected) {
  // The eight pairs on short runs and small budgets (a couple of seconds): the
  // summary's pair counts are those of the cases it lists, read from round 1's
  // top two and from the selection.
  const int rc =
      run("diagnose-selfcheck --effects creep --seeds 1 --null 0 --train-s 10 --heldout-s 10 --evaluations 20 "
          "--evaluations-per-parameter 0 --screen-evaluations 0 --out " +
          file("pairs.json"));
  ASSERT_TRUE(rc == 0 || rc == 1) << err_;
  const auto j = nlohmann::json::parse(slurp(file("pairs.json")));
  int pairs = 0, top2 = 0, selected = 0;
  for (const auto& c : j["cases"]) {
    const auto& w = c["withheld"];
    if (w.size() != 2) continue;
    ++pairs;
    auto among = [&](const nlohmann::json& list) {
      int n = 0;
      for (const auto& e : w) n += std::find(list.begin(), list.end(), e) != list.end();
      return n == 2;
    };
    top2 += among(c["top2"]);
    selected += among(c["selected"]);
  }
  EXPECT_EQ(pairs, 8);
  EXPECT_EQ(j["summary"]["pair_cases"], pairs);
  EXPECT_EQ(j["summary"]["pair_top2"], top2);
  EXPECT_EQ(j["summary"]["pair_both_selected"], selected);
  EXPECT_NE(slurp(file("stdout.txt")).find("pairs with both effects selected: " + std::to_string(selected) + "/8"),
            std::string::npos);
}

TEST_F(Cli, SelfcheckRunsFromAJoystickWhenAsked) {
  // One deadzone case on short runs and a small budget: the runs it saves are
  // the joystick's (from rest, smooth), and the results say so.
  fs::create_directories(file("joy_runs"));
  const int rc =
      run("diagnose-selfcheck --excitation joystick --effects deadzone --seeds 1 --no-pairs --null 0 --train-s 10 "
          "--heldout-s 10 --evaluations 20 --evaluations-per-parameter 0 --screen-evaluations 0 --save-runs " +
          file("joy_runs") + " --out " + file("joy.json"));
  ASSERT_TRUE(rc == 0 || rc == 1) << err_;
  EXPECT_EQ(nlohmann::json::parse(slurp(file("joy.json")))["excitation"], "joystick");
  EXPECT_NE(slurp(file("stdout.txt")).find("independent laws (joystick runs)"), std::string::npos);
  const plsa::io::Log train = plsa::io::readCsvLog(file("joy_runs") + "/deadzone__logistic___1_train.csv");
  const Eigen::MatrixXd u = train.columnsOf({"cmd_1", "cmd_2", "cmd_3"});
  ASSERT_EQ(u.rows(), 800);
  EXPECT_EQ(u.row(0).norm(), 0.0);
  EXPECT_LT((u.bottomRows(u.rows() - 1) - u.topRows(u.rows() - 1)).cwiseAbs().maxCoeff(), 0.02);
  EXPECT_EQ(run("diagnose-selfcheck --excitation stairs --out " + file("no.json")), 2);
  EXPECT_NE(err_.find("--excitation"), std::string::npos) << err_;
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
                " --no-identified-reference --out " + file("dg")),
            0)
      << err_;
  const auto d = nlohmann::json::parse(slurp(file("dg") + "/diagnosis.json"));
  EXPECT_FALSE(d["identified_reference"]["available"].get<bool>());
  EXPECT_NE(d["identified_reference"]["note"].get<std::string>().find("not computed"), std::string::npos);
  // The self-check diagnoses its runs as read back from these logs, so the command reproduces
  // the case to the digit (the calibrations' paths follow the readings' last digits: fed the
  // recorded bending vectors instead, a case's verdict was seen to change from nothing to two
  // effects). Recorded from rest and replayed so: a case misread as settled gave 18.1% for 11.3%.
  const auto& seen = j["cases"][0];
  EXPECT_EQ(d["gap_before"].get<double>(), seen["gap_before"].get<double>());
  EXPECT_EQ(d["gap_after"].get<double>(), seen["gap_after"].get<double>());
  EXPECT_EQ(d["selected"], seen["selected"]);
  EXPECT_EQ(d["selected"][0], "deadzone");
  for (const char* f : {"trace.csv", "gap_map.csv", "shrink.csv"}) EXPECT_TRUE(fs::exists(file("dg") + "/" + f)) << f;
}
