// candump bus logs as logs: lines parsed strictly, frames decoded with the
// signal map, rows on the pressure sensors' grid holding each signal's latest
// value, and every defect named with its line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "plsa/can/candump_log.hpp"
#include "plsa/io/log_readers.hpp"
#include "support/refusals.hpp"

namespace plsa::can {
namespace {

struct Bus {
  SignalMap map = defaultSignalMap();
  std::ostringstream text;
  std::uint8_t counter[3] = {0, 0, 0};

  void send(const char* message, double t, std::vector<double> values, int k) {
    CanFrame f;
    ASSERT_TRUE(encodeFrame(map.message(message), values.data(), counter[k]++, f));
    text << candumpLine(t, "can0", f);
  }
};

// A 100 Hz sensor, commands at 50 Hz, the tip at 100 Hz, 0.5 s, starting at
// an epoch time as candump writes it; the sensed pressure is a ramp.
Bus rampRecording() {
  Bus bus;
  const double t0 = 1764150000.000100;
  for (int k = 0; k < 50; ++k) {
    const double t = t0 + 0.01 * k;
    if (k % 2 == 0) bus.send("valve_command", t + 0.0002, {0.1 + 0.001 * k, 0.2, 0.0}, 0);
    bus.send("pressure_sensor", t + 0.0005, {0.01 * k, 0.3, 0.0}, 1);
    bus.send("tip_angle", t + 0.0007, {5.0 + 0.1 * k, -30.0}, 2);
  }
  return bus;
}

io::Log read(const std::string& text, const SignalMap& map = defaultSignalMap()) {
  std::istringstream in(text);
  return readCandumpLog(in, "bus.log", map);
}

TEST(CandumpLog, RowsFollowTheSensorsGridWithTheLatestValueOfEachSignal) {
  const io::Log log = read(rampRecording().text.str());
  const std::vector<std::string> expected = {"time_s", "p_1",   "p_2",      "p_3",      "cmd_1",
                                             "cmd_2",  "cmd_3", "bend_deg", "steer_deg"};
  EXPECT_EQ(log.columns, expected);
  // One row per 10 ms sensor cycle from the first, whose cycle also holds the
  // first command (0.3 ms before it) and tip frame (0.2 ms after it).
  ASSERT_EQ(log.samples(), 50);
  EXPECT_NEAR(std::stod(log.metadata.at("sample_time_s")), 0.01, 1e-9);
  for (Eigen::Index r = 0; r < log.samples(); ++r) {
    EXPECT_NEAR(log.data(r, 0), 0.01 * static_cast<double>(r), 1e-6);  // candump writes microseconds
    // Row r is step r's cycle: its sensor and tip frames, the last command.
    EXPECT_NEAR(log.data(r, 1), 0.01 * static_cast<double>(r), 1e-5);
    EXPECT_NEAR(log.data(r, 2), 0.3, 1e-5);
    const int command_step = static_cast<int>(r) / 2 * 2;  // commands only every other step
    EXPECT_NEAR(log.data(r, 4), 0.1 + 0.001 * command_step, 1e-5);
    EXPECT_NEAR(log.data(r, 7), 5.0 + 0.1 * static_cast<double>(r), 0.01);
    EXPECT_NEAR(log.data(r, 8), -30.0, 0.01);
  }
  EXPECT_TRUE(log.warnings.empty()) << log.warnings.front();
}

TEST(CandumpLog, BadFramesAreDroppedAndCountedNotRead) {
  Bus bus = rampRecording();
  std::string text = bus.text.str();
  // Corrupt one sensor frame's checksum byte (its last two hex digits).
  const auto at = text.find("200#", text.size() / 2);
  const auto end = text.find('\n', at);
  text[end - 1] = text[end - 1] == '0' ? '1' : '0';
  // Frames plsa does not map, of every kind candump writes.
  text +=
      "(1764150000.600000) can0 7FF#00\n(1764150000.600001) can0 1FFFFFFF#0011\n"
      "(1764150000.600002) can0 123#R\n(1764150000.600003) can1 123##1AABB\n";
  const io::Log log = read(text);
  std::string all;
  for (const auto& w : log.warnings) all += w + "\n";
  EXPECT_NE(all.find("1 pressure_sensor (checksum mismatch) frames dropped"), std::string::npos) << all;
  EXPECT_NE(all.find("1 counter gaps in pressure_sensor"), std::string::npos) << all;
  EXPECT_NE(all.find("1 frames of ids the signal map does not read"), std::string::npos) << all;
  EXPECT_NE(all.find("1 extended, 1 remote and 1 CAN FD frames skipped"), std::string::npos) << all;
  EXPECT_NE(all.find("several interfaces (can0, can1)"), std::string::npos) << all;
  EXPECT_EQ(log.samples(), 50);  // the dropped frame's row holds the frame before it
}

TEST(CandumpLog, MalformedLinesAreNamedWithTheirLineNumber) {
  const std::string good = "(1764150000.000100) can0 200#0000000000000000\n";
  const std::vector<test::Refusal> second_lines = {
      {"1764150000.000100 can0 200#00", "time stamp"},
      {"(1764150000) can0 200#00", "time stamp"},
      {"(17641x0000.000100) can0 200#00", "time stamp"},
      {"(1764150000.000100) can0 2000#00", "3 or 8 hex digits"},
      {"(1764150000.000100) can0 200-00", "id#data"},
      {"(1764150000.000100) can0 200#0", "0 to 8 bytes"},
      {"(1764150000.000100) can0 200#001122334455667788", "0 to 8 bytes"},
      {"(1764150000.000100) can0 200#zz", "0 to 8 bytes"},
      {"(1764150000.000100) can0 800#00", "at most 7FF"},
      {"(1764150000.000100) can0", "not a candump log line"},
      {"(1764150000.000100) can0 200#00 X", "not a candump log line"},
      {"(1764150000.000100) can0 200#00" + std::string(300, ' '), "longer than 256 bytes"},
      // Found by a probe: a name with escape sequences reached the terminal in a warning, one with a NUL cut it.
      {"(1764150000.000100) \x1b]0;pwned\x07\x1b[2J 200#00", "the interface name is not 1 to 15 printable ASCII"},
      {std::string("(1764150000.000100) ca\0n1 200#00", 32), "the interface name is not 1 to 15 printable ASCII"},
      {"(1764150000.000100) can0123456789abcdef 200#00", "the interface name is not 1 to 15 printable ASCII"},
  };
  test::expectEachRefused<std::runtime_error>(
      second_lines, [&](const std::string& line) { read(good + line + "\n"); }, "bus.log:2: ");
}

TEST(CandumpLog, TooFewSensorFramesOrAnotherBusSaySo) {
  EXPECT_THROW(read(""), std::runtime_error);
  try {  // frames, but none the profile reads as the pressure sensor
    read("(1.000000) can0 123#00\n(1.010000) can0 123#00\n(1.020000) can0 123#00\n");
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("0 pressure_sensor frames"), std::string::npos) << e.what();
  }
  const std::string text = rampRecording().text.str();
  // A stamp far off (found by the fuzzer) would size a grid of 10^11 rows.
  std::string far = text;
  const auto last_sensor = far.rfind(") can0 200#");
  far.replace(far.rfind('(', last_sensor) + 1, 4, "3528");
  try {
    read(far);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("most rows would be gaps"), std::string::npos) << e.what();
  }
  const auto first = text.rfind('\n', text.find("200#")) + 1;  // the first sensor frame, again at the end
  try {
    read(text + text.substr(first, text.find('\n', first) + 1 - first));
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("older than the one before it"), std::string::npos) << e.what();
  }
  // Every frame logged twice (found by a probe) was said to "share one time stamp".
  std::string twice;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) twice += line + "\n" + line + "\n";
  try {
    read(twice);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("half or more of the pressure_sensor frames repeat the time stamp before "
                                         "them (frames logged twice?)"),
              std::string::npos)
        << e.what();
  }
}

TEST(CandumpLog, TheRegistryKnowsItByContentAndTheProfileDecidesTheIds) {
  io::LogReaderRegistry registry;
  registry.add(io::csvLogFormat());
  registerLogFormats(registry);
  const std::string text = rampRecording().text.str();
  ASSERT_EQ(registry.recognise("candump-2026-11-26_120000.log", text.substr(0, io::kSniffBytes))->name, "candump");
  ASSERT_EQ(registry.recognise("run.csv", "time_s,p_1\n0,0\n")->name, "csv");
  std::istringstream in(text);
  EXPECT_EQ(registry.read(in, "bus.log").samples(), 50);
  // A required column the bus does not carry is named.
  io::ReadOptions needs;
  needs.required = {"p_1", "flow"};
  std::istringstream again(text);
  try {
    registry.read(again, "bus.log", needs);
    ADD_FAILURE();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no column 'flow'"), std::string::npos) << e.what();
  }
  // Another profile moves the sensor's id: the same log then has no sensor frames.
  SignalMap moved = defaultSignalMap();
  for (auto& m : moved.messages)
    if (m.name == "pressure_sensor") m.id = 0x300;
  EXPECT_THROW(read(text, moved), std::runtime_error);
}

// A signal whose scale is coarser than its column's whole span would write a
// varying column as one or two levels (commands under 0.5 bar at a scale of -1
// all became 0): refused, naming the signal, its step and the column's span.
TEST(CandumpLog, ASignalTooCoarseForItsColumnIsRefused) {
  io::Log log;
  log.source = "run.csv";
  log.columns = {"time_s", "cmd_1", "cmd_2", "cmd_3", "p_1", "p_2", "p_3"};
  log.data.setZero(20, 7);
  for (Eigen::Index r = 0; r < 20; ++r) {
    log.data(r, 0) = 0.0125 * static_cast<double>(r);
    log.data(r, 1) = 0.02 * static_cast<double>(r);  // 0 .. 0.38 bar
    log.data(r, 4) = 0.01 * static_cast<double>(r);
  }
  const std::string path = ::testing::TempDir() + "coarse.candump";
  writeCandumpLog(path, log, defaultSignalMap());  // the default's 1e-5 bar steps carry it
  SignalMap steady = defaultSignalMap();           // a column moving under 1 mbar is steady: its noise may go
  for (auto& m : steady.messages)
    if (m.name == "valve_command") m.signals[1].scale = 0.01;
  for (Eigen::Index r = 0; r < 20; ++r) log.data(r, 2) = 0.2 + 4e-5 * static_cast<double>(r % 3);
  writeCandumpLog(path, log, steady);
  for (double scale : {-1.0, 1e308, 0.5}) {
    SignalMap coarse = defaultSignalMap();
    for (auto& m : coarse.messages)
      if (m.name == "valve_command") m.signals[0].scale = scale;
    try {
      writeCandumpLog(path, log, coarse);
      ADD_FAILURE() << "scale " << scale << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("valve_command.setpoint_1 steps by"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("cmd_1 of run.csv spans only 0.38"), std::string::npos) << e.what();
    }
  }
  std::remove(path.c_str());
}

// candump's (seconds.micros) stamp has no sign: a negative time_s, which its
// reader would refuse, is refused when writing, naming the row.
TEST(CandumpLog, ATimeCandumpCannotStampIsRefusedWhenWriting) {
  io::Log log;
  log.source = "shifted.csv";
  log.columns = {"time_s", "cmd_1", "cmd_2", "cmd_3", "p_1", "p_2", "p_3"};
  log.data.setZero(4, 7);
  for (Eigen::Index r = 0; r < 4; ++r) log.data(r, 0) = -0.0125 + 0.0125 * static_cast<double>(r);
  const std::string path = ::testing::TempDir() + "shifted.candump";
  try {
    writeCandumpLog(path, log, defaultSignalMap());
    ADD_FAILURE() << "a negative time was written";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("row 1 of shifted.csv: time_s is not a time candump writes"),
              std::string::npos)
        << e.what();
  }
  log.data.col(0).array() += 0.0125;  // from 0: written and read back
  writeCandumpLog(path, log, defaultSignalMap());
  std::remove(path.c_str());
}

}  // namespace
}  // namespace plsa::can
