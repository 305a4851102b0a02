// Writes the fuzz targets' seed inputs and the regression inputs of the
// defects found by hand (issue: hostile input) into tests/fuzz/corpus/<target>/.
// Build target `fuzz_seeds` (not built by default); run it with the corpus
// folder as its argument after a format changes, and commit what it writes:
//   cmake --build build --target fuzz_seeds && build/tests/fuzz_seeds tests/fuzz/corpus
#include <array>
#include <cstdio>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/prediction_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/can/candump_log.hpp"
#include "plsa/can/dbc.hpp"
#include "plsa/can/udp_transport.hpp"
#include "plsa/lcm/lcm_log.hpp"
#include "plsa/model/model_file.hpp"
#include "plsa/sim/experiment.hpp"
#include "plsa/sim/sim_config.hpp"
#include "support/lcm_bytes.hpp"

namespace fs = std::filesystem;

namespace {

fs::path root;

void put(const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(root / target);
  std::ofstream(root / target / name, std::ios::binary) << bytes;
}

using plsa::test::encoded;
using plsa::test::withInt32;

std::string replaceFirst(std::string s, const std::string& what, const std::string& with) {
  const auto at = s.find(what);
  if (at == std::string::npos) throw std::runtime_error("make_seeds: '" + what + "' not found");
  return s.replace(at, what.size(), with);
}

void csvSeeds() {
  const std::string good = "# source: seed\ntime_s,p_1,bend_deg\n0.0125,0.1,1.5\n0.025,0.2,2.5\n0.0375,0.3,3.5\n";
  put("csv_log", "seed-small.csv", good);
  put("csv_log", "regression-bom-hides-time.csv", "\xEF\xBB\xBF" + good.substr(good.find('\n') + 1));
  put("csv_log", "regression-cut-in-last-field.csv", good.substr(0, good.size() - 3));
  put("csv_log", "regression-nul-byte.csv", std::string("time_s,p_1\n0.1,\0\n", 17));
  put("csv_log", "regression-time-back.csv", "time_s,p_1\n0.2,1\n0.1,2\n");
  put("csv_log", "regression-nan.csv", "time_s,p_1\n0.1,nan\n");
}

plsa::DioPwlObfModel smallModel() {
  plsa::DioPwlObfModel m;
  m.inputs = {"p_1", "p_2"};
  m.outputs = {"bend_deg"};
  m.input_min = 0.0;
  m.input_max = 0.4;
  m.poles = {{plsa::PoleSet({{0.5, 0.0}, {0.8, 0.0}}), plsa::PoleSet({{0.6, 0.1}, {0.6, -0.1}})}};
  m.shaping.play = {{plsa::PlayChannel(0.0)}, {plsa::PlayChannel(0.0), plsa::PlayChannel(0.05)}};
  m.partition = plsa::PwlPartition({0}, {{0.2}});
  for (int r = 0; r < 2; ++r) {
    m.coefficients.push_back({Eigen::VectorXd::LinSpaced(m.regressorSize(0), 0.1, 1.0 + r)});
    m.region_fits.push_back({100, -1, ""});
  }
  return m;
}

void modelSeeds() {
  const std::string good = plsa::modelToJson(smallModel());
  put("model_file", "seed-small.json", good);
  put("model_file", "regression-number-beyond-double.json",
      replaceFirst(good, "\"sample_time_s\": 0.0125", "\"sample_time_s\": 1e400"));
  put("model_file", "regression-null-range.json",
      replaceFirst(good, "\"input_range\": [\n  0.0", "\"input_range\": [\n  null"));
  put("model_file", "regression-huge-version.json", replaceFirst(good, "\"version\": 2", "\"version\": 1e300"));
  put("model_file", "regression-huge-samples.json", replaceFirst(good, "\"samples\": 100", "\"samples\": 1e300"));
  put("model_file", "regression-inf-string-bound.json", replaceFirst(good, "0.0,\n  0.4\n ]", "0.0,\n  \"-inf\"\n ]"));
  put("model_file", "regression-duplicate-key.json",
      replaceFirst(good, "\"sample_time_s\"", "\"sample_time_s\": 1, \"sample_time_s\""));
  put("model_file", "regression-unknown-key.json",
      replaceFirst(good, "\"sample_time_s\"", "\"from_the_future\": 1, \"sample_time_s\""));
  put("model_file", "regression-duplicate-output.json",
      replaceFirst(good, "\"inputs\": [\n  \"p_1\",\n  \"p_2\"", "\"inputs\": [\n  \"p_1\",\n  \"p_1\""));
  put("model_file", "regression-nul-in-name.json",
      replaceFirst(good, "\"inputs\": [\n  \"p_1\"", "\"inputs\": [\n  \"p\\u0000_1\""));
  put("model_file", "regression-deep-nesting.json", std::string(5000, '[') + std::string(5000, ']'));
  // Two inputs of 1100 breakpoints each: 1.2 million cells, past the partition's limit (an int product before).
  std::string many = "[";
  for (int i = 1; i <= 1100; ++i) many += std::to_string(i) + (i < 1100 ? "," : "]");
  std::string huge = replaceFirst(good, "\"breakpoints\": [\n   [\n    0.2\n   ]\n  ]",
                                  "\"breakpoints\": [" + many + "," + many + "]");
  put("model_file", "regression-huge-partition.json",
      replaceFirst(huge, "\"inputs\": [\n   0\n  ]", "\"inputs\": [0, 1]"));
}

void simConfigSeeds() {
  const std::string good = plsa::sim::simConfigToJson(plsa::sim::SimConfig{});
  put("sim_config", "seed-default.json", good);
  put("sim_config", "regression-number-beyond-double.json",
      replaceFirst(good, "\"sample_rate_hz\": 80.0", "\"sample_rate_hz\": 1e400"));
  put("sim_config", "regression-duplicate-key.json",
      replaceFirst(good, "\"sample_rate_hz\"", "\"sample_rate_hz\": 10, \"sample_rate_hz\""));
}

void signalMapSeeds() {
  const std::string two =
      R"({"profile":"p","messages":[)"
      R"({"name":"valve_command","id":256,"dlc":8,"signals":[{"name":"a","byte":0,"bits":16,"scale":1e-5,"unit":"bar"}]},)"
      R"({"name":"pressure_sensor","id":256,"dlc":8,"signals":[{"name":"b","byte":0,"bits":16,"scale":1e-5,"unit":"bar"}]}]})";
  put("signal_map", "regression-one-id-two-messages.json", two);
  put("signal_map", "regression-duplicate-signal.json",
      R"({"profile":"p","messages":[{"name":"m","id":1,"dlc":8,"signals":[{"name":"a","byte":0,"bits":16,"scale":1},{"name":"a","byte":2,"bits":16,"scale":1}]}]})");
  put("signal_map", "seed-default.dbc", plsa::can::signalMapToDbc(plsa::can::defaultSignalMap()));
  // Found by fuzz_signal_map: a unit that is no UTF-8 read from DBC, which JSON cannot write.
  put("signal_map", "regression-unit-not-utf8.dbc",
      replaceFirst(plsa::can::signalMapToDbc(plsa::can::defaultSignalMap()), "\"deg\"", "\"d\xE9g\""));
  // Found by fuzz_signal_map in CI: a unit "\" read as a backslash, written back it opened a string.
  put("signal_map", "regression-backslash-unit.dbc",
      replaceFirst(plsa::can::signalMapToDbc(plsa::can::defaultSignalMap()), "\"bar\"", "\"\\\""));
  put("signal_map", "seed-motorola-and-comments.dbc",
      "VERSION \"\"\nBU_: A\nBO_ 512 s: 8 A\n SG_ p : 7|16@0- (0.5,-1) [0|0] \"bar\" A\n"
      " SG_ counter : 48|8@1+ (1,0) [0|255] \"\" A\nCM_ \"two\n SG_ lines\";\n");
}

void candumpSeeds() {
  const plsa::can::SignalMap map = plsa::can::defaultSignalMap();
  std::string good;
  for (int k = 0; k < 4; ++k)
    for (const char* name : {"valve_command", "pressure_sensor", "tip_angle"}) {
      const std::vector<double> values = std::string(name) == "tip_angle" ? std::vector<double>{10.0 + k, -20.0}
                                                                          : std::vector<double>{0.1 * k, 0.2, 0.0};
      plsa::can::CanFrame f;
      if (!plsa::can::encodeFrame(map.message(name), values.data(), static_cast<std::uint8_t>(k), f))
        throw std::runtime_error("make_seeds: a seed frame does not encode");
      good += plsa::can::candumpLine(1764150000.0 + 0.0125 * k, "can0", f);
    }
  put("candump_log", "seed-four-cycles.log", good);
  put("candump_log", "seed-other-kinds.log",
      good +
          "(1764150001.000000) can1 1FFFFFFF#00\n(1764150001.000001) can0 123#R\n(1764150001.000002) can0 123##1AA\n");
  put("candump_log", "regression-time-back.log", good + good.substr(0, good.find('\n') + 1));
  put("candump_log", "regression-one-sensor-frame.log", good.substr(0, good.find("210#")));
  // Found by fuzz_candump_log: one stamp 56 years on sized a grid of 10^11 rows.
  put("candump_log", "regression-stamp-far-off.log",
      replaceFirst(good, "(1764150000.037500) can0 200", "(3528300000.037500) can0 200"));
  put("candump_log", "regression-long-line.log", "(1.000000) can0 200#00" + std::string(400, ' ') + "\n");
}

void datagramSeeds() {
  plsa::can::CanFrame f;
  f.id = 0x200;
  f.dlc = 8;
  f.data = {1, 2, 3, 4, 5, 6, 7, 8};
  std::array<std::uint8_t, plsa::can::kUdpCanDatagramSize> d{};
  plsa::can::encodeDatagram(plsa::can::DatagramKind::kFrame, f, d);
  put("udp_datagram", "seed-frame", std::string(d.begin(), d.end()));
  f.data = {2, 0, 0, 0, 0, 0, 0, 0};
  plsa::can::encodeDatagram(plsa::can::DatagramKind::kBusState, f, d);
  put("udp_datagram", "seed-bus-off", std::string(d.begin(), d.end()));
}

plsa_lcm::actuator_state_t state(std::int64_t utime, std::int32_t chambers) {
  return plsa::test::stateMessage(utime, utime / 12500, chambers);
}

void lcmMessageSeeds() {
  plsa_lcm::pressure_command_t c{};
  c.utime = 1;
  c.seq = 1;
  c.n_chambers = 3;
  c.pressure_bar = {0.1, 0.2, 0.0};
  const std::string cmd = encoded(c);
  put("lcm_command", "seed-three-chambers", cmd);
  // n_chambers sits after the fingerprint, utime and seq (8 + 8 + 8 bytes).
  put("lcm_command", "regression-negative-chambers", withInt32(cmd.substr(0, 28), 24, 0xFFFFFFFFu));
  put("lcm_command", "regression-huge-chambers", withInt32(cmd.substr(0, 28), 24, 0x10000000u));
  const std::string st = encoded(state(12500, 3));
  put("lcm_state", "seed-three-chambers", st);
  put("lcm_state", "regression-negative-chambers", withInt32(st, 24, 0xFFFFFFFEu));
  plsa_lcm::prediction_t p{};
  p.horizon = 2;
  p.n_outputs = 2;
  p.output_names = {"bend_deg", "steer_deg"};
  p.trajectory = {{1, 2}, {3, 4}};
  put("lcm_prediction", "seed-two-steps", encoded(p));
  plsa_lcm::status_t s{};
  s.source = "plsa sim";
  s.message = "running";
  s.n_values = 1;
  s.names = {"states"};
  s.values = {3};
  const std::string status = encoded(s);
  put("lcm_status", "seed-one-value", status);
  // The source string's length follows the fingerprint and utime (8 + 8 bytes).
  put("lcm_status", "regression-negative-string-length", withInt32(status, 16, 0xFFFFFFF0u));
}

std::string event(std::int64_t n, const std::string& channel, const std::string& data) {
  std::string e;
  auto be = [&](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) e.push_back(static_cast<char>(v >> (8 * i)));
  };
  be(plsa::lcm::kLcmLogSyncWord, 4);
  be(static_cast<std::uint64_t>(n), 8);
  be(static_cast<std::uint64_t>(n) * 12500, 8);
  be(channel.size(), 4);
  be(data.size(), 4);
  return e + channel + data;
}

void lcmLogSeeds() {
  const std::string log = event(0, "PLSA_STATE", encoded(state(12500, 3))) + event(1, "OTHER", "xyz") +
                          event(2, "PLSA_STATE", encoded(state(25000, 3)));
  put("lcm_log", "seed-two-states", log);
  put("lcm_log", "regression-huge-data-length",
      withInt32(event(0, "PLSA_STATE", encoded(state(12500, 3))), 24, 0x7FFFFFFFu));
  put("lcm_log", "regression-huge-chambers-logged",
      event(0, "PLSA_STATE", withInt32(encoded(state(12500, 3)), 24, 0x10000000u)));
  put("lcm_log", "regression-cut-mid-event", log.substr(0, log.size() - 10));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: fuzz_seeds <corpus folder>\n";
    return 2;
  }
  root = argv[1];
  csvSeeds();
  modelSeeds();
  simConfigSeeds();
  signalMapSeeds();
  candumpSeeds();
  datagramSeeds();
  lcmMessageSeeds();
  lcmLogSeeds();
  std::cout << "seeds written to " << root << "\n";
  return 0;
}
