// The tools against hostile files, the CAN tools and bus logs: named errors, nothing overwritten.
#include <gtest/gtest.h>

#include <algorithm>
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

// A small valid model of p_1, p_2 -> bend_deg (schema version 2, tests/data),
// as text with its first coefficient set.
std::string smallModelJson(double first_coefficient) {
  std::ifstream in(std::string(PLSA_SOURCE_DIR) + "/tests/data/small_model.json");
  nlohmann::json j = nlohmann::json::parse(in);
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

  {  // A log declaring other units than the model's is warned of (a probe: validated without a word).
    std::string text = log_before;
    const std::string bar = "p_* bar gauge";
    ASSERT_NE(text.find(bar), std::string::npos);
    text.replace(text.find(bar), bar.size(), "p_* kPa");
    std::ofstream(file("kpa.csv")) << text;
  }
  ASSERT_EQ(run("validate --model " + file("m.json") + " --log " + file("kpa.csv") + " --horizons 40"), 0) << err_;
  EXPECT_NE(err_.find("plsa validate: warning: " + file("kpa.csv") + " declares '# units: time_s s; cmd_*, p_* kPa; " +
                      "bend_deg, steer_deg deg', which never says bar: the model's inputs are in bar"),
            std::string::npos)
      << err_;
  EXPECT_EQ(err_.find("which never says deg"), std::string::npos) << err_;
  ASSERT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --horizons 40"), 0) << err_;
  EXPECT_EQ(err_.find("never says"), std::string::npos) << err_;

  // Zero samples once ended in SIGSEGV.
  EXPECT_EQ(run("simulate --experiment joystick --duration 0.006 --out " + file("x.csv")), 1);
  EXPECT_NE(err_.find("joystick: a duration of 0.006 s is under two samples at 80 Hz"), std::string::npos) << err_;
  // An endless file as a model grew without bound.
  EXPECT_EQ(run("validate --model /dev/zero --log " + file("j.csv")), 1);
  EXPECT_NE(err_.find("/dev/zero: the model file is larger than 64 MiB"), std::string::npos) << err_;

  // An output in a folder that does not exist is named before the work (a probe: identify and validate
  // failed at the write, after all of it).
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --out " + file("no/such/m.json")), 1);
  EXPECT_NE(err_.find("plsa identify: --out " + file("no/such/m.json") + ": the folder " + file("no/such") +
                      " does not exist"),
            std::string::npos)
      << err_;
  EXPECT_EQ(err_.find("[2/5]"), std::string::npos) << "identification ran: " << err_;
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --json " + file("no/v.json")), 1);
  EXPECT_NE(err_.find("plsa validate: --json " + file("no/v.json") + ": the folder"), std::string::npos) << err_;
  // An empty output path is a usage error naming the option (`--csv ''` was taken as not given).
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --csv ''"), 2);
  EXPECT_NE(err_.find("--csv: an empty path names no file"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --out ''"), 2);
  EXPECT_NE(err_.find("--out: an empty path names no file"), std::string::npos) << err_;
  // Outputs never replace inputs: the training log, the model, the validation log.
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --out " + file("j.csv")), 1);
  EXPECT_NE(err_.find("--out " + file("j.csv") + " is an input"), std::string::npos) << err_;
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --json " + file("m.json")), 1);
  EXPECT_NE(err_.find("plsa never writes over what it reads"), std::string::npos) << err_;
  fs::create_symlink(file("j.csv"), file("link.csv"));
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("j.csv") + " --csv " + file("link.csv")), 1);
  EXPECT_NE(err_.find("is the input " + file("j.csv")), std::string::npos) << err_;
  EXPECT_EQ(run("simulate --config " + file("m.json") + " --experiment joystick --out " + file("m.json")), 1);
  // The signal map a log is decoded with is an input too.
  ASSERT_EQ(run("can-profile --out " + file("profile.json")), 0) << err_;
  EXPECT_EQ(run("convert --in " + file("j.csv") + " --can-profile " + file("profile.json") + " --out " +
                file("profile.json")),
            1);
  EXPECT_NE(err_.find("plsa never writes over what it reads"), std::string::npos) << err_;
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --can-profile " + file("profile.json") + " --out " +
                file("profile.json")),
            1);
  EXPECT_NE(err_.find("plsa never writes over what it reads"), std::string::npos) << err_;
  // A partition the data cannot determine: refused at once, not hours of solves.
  EXPECT_EQ(run("identify --log " + file("j.csv") + " --levels 12 --out " + file("x12.json")), 1);
  EXPECT_NE(err_.find("coefficients per output (regions x inputs x poles), more than the 1680 samples can determine"),
            std::string::npos)
      << err_;
  // A report folder that is a file: refused before any calibration.
  EXPECT_EQ(run("diagnose --sim " + file("m.json") + " --real " + file("j.csv") + " --out " + file("m.json")), 1);
  EXPECT_NE(err_.find("--out " + file("m.json") + " exists and is not a folder"), std::string::npos) << err_;
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
  EXPECT_EQ(err_.find("warning"), std::string::npos) << err_;  // every column carried
  {  // A column the bus does not carry is said, not listed as written (a probe).
    std::ifstream in(file("j.csv"));
    std::ofstream out(file("with_temp.csv"));
    for (std::string line; std::getline(in, line);)
      out << line << (line[0] == '#' ? "" : line.rfind("time_s", 0) == 0 ? ",temp_c" : ",21.5") << "\n";
  }
  ASSERT_EQ(run("convert --in " + file("with_temp.csv") + " --out " + file("t.candump")), 0) << err_;
  EXPECT_NE(err_.find("plsa convert: warning: " + file("t.candump") +
                      " holds no column for temp_c (its format carries "
                      "only time_s, p_1"),
            std::string::npos)
      << err_;
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
  EXPECT_NE(err_.find("row 1 of " + file("high.csv") + ": pressure_sensor."), std::string::npos) << err_;
  EXPECT_NE(err_.find(" cannot carry p_1 = 0.9 (its range is 0 to 0.65535)"), std::string::npos) << err_;
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

// A log from a pipe, as shells hand one (/dev/stdin, <(...)); a device that
// is no log refused before it is read; a constant output named.
TEST_F(Cli, ValidateReadsALogFromAPipe) {
  ASSERT_EQ(run("simulate --experiment joystick --duration 20 --seed 2 --out " + file("j.csv")), 0) << err_;
  std::ofstream(file("m.json")) << smallModelJson(0.1);
  const std::string piped = "cat " + file("j.csv") + " | " + exe_ + " validate --model " + file("m.json") +
                            " --log /dev/stdin --horizons 40 > " + file("out.txt") + " 2> " + file("err.txt");
  EXPECT_EQ(WEXITSTATUS(std::system(piped.c_str())), 0) << slurp(file("err.txt"));
  EXPECT_NE(slurp(file("out.txt")).find("bend_deg"), std::string::npos) << slurp(file("out.txt"));

  EXPECT_EQ(run("convert --in /dev/zero --out " + file("zero.csv")), 1);
  EXPECT_NE(err_.find("convert: /dev/zero: not a log file"), std::string::npos) << err_;
  EXPECT_FALSE(fs::exists(file("zero.csv")));

  {  // bend_deg held at 5 deg throughout
    std::ifstream in(file("j.csv"));
    std::ofstream out(file("still.csv"));
    int bend = -1;
    for (std::string line; std::getline(in, line);) {
      if (line.empty() || line[0] == '#') continue;
      std::vector<std::string> cells;
      std::stringstream ss(line);
      for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
      if (bend < 0) {
        bend = static_cast<int>(std::find(cells.begin(), cells.end(), "bend_deg") - cells.begin());
        ASSERT_LT(bend, static_cast<int>(cells.size()));
      } else {
        cells[static_cast<std::size_t>(bend)] = "5";
      }
      for (std::size_t i = 0; i < cells.size(); ++i) out << (i ? "," : "") << cells[i];
      out << "\n";
    }
  }
  EXPECT_EQ(run("validate --model " + file("m.json") + " --log " + file("still.csv") + " --horizons 40"), 1);
  EXPECT_NE(err_.find("still.csv: output 'bend_deg' is constant over the scored samples"), std::string::npos) << err_;
}
