#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "plsa/lcm/lcm_log.hpp"
#include "plsa/sim/experiment.hpp"

namespace fs = std::filesystem;

namespace {
std::string tempPath(const std::string& name) {
  return (fs::temp_directory_path() / ("plsa_" + std::to_string(::getpid()) + "_" + name)).string();
}
}  // namespace

TEST(LcmLog, RoundTripsASimulatedRunAndDispatchesByExtension) {
  plsa::sim::ExperimentOptions o;
  o.joystick_duration_s = 5;
  plsa::sim::Actuator a(plsa::sim::SimConfig{}, 2);
  const plsa::io::Log log = plsa::sim::runExperiment(a, plsa::sim::joystickExperiment(o));
  const std::string lcm_path = tempPath("rt.lcmlog"), csv_path = tempPath("rt.csv");
  plsa::lcm::writeLcmLog(lcm_path, log);
  plsa::io::writeCsvLog(csv_path, log);
  const plsa::io::Log from_lcm = plsa::lcm::readLogFile(lcm_path);
  const plsa::io::Log from_csv = plsa::lcm::readLogFile(csv_path);
  ASSERT_EQ(from_lcm.samples(), log.samples());
  EXPECT_EQ(from_lcm.columns, log.columns);
  // Time goes through integer microseconds; everything else is exact.
  EXPECT_LT((from_lcm.column("time_s") - log.column("time_s")).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(from_lcm.data.rightCols(8), log.data.rightCols(8));
  EXPECT_EQ(from_csv.data, log.data);
  fs::remove(lcm_path);
  fs::remove(csv_path);
}

TEST(LcmLog, MalformedFilesAreClearErrors) {
  const std::string junk = tempPath("junk.lcmlog");
  std::ofstream(junk) << "this is not an LCM event log";
  EXPECT_THROW(plsa::lcm::readLcmLog(junk), std::runtime_error);
  EXPECT_THROW(plsa::lcm::readLcmLog(tempPath("missing.lcmlog")), std::runtime_error);

  plsa::io::Log log;
  log.columns = {"time_s", "cmd_1", "cmd_2", "cmd_3", "p_1", "p_2", "p_3", "bend_deg", "steer_deg"};
  log.data = Eigen::MatrixXd::Zero(3, 9);
  log.data.col(0) << 0.0125, 0.025, 0.0375;
  const std::string good = tempPath("good.lcmlog");
  // Microseconds since the epoch in the time column: beyond an int64 utime, refused naming the row.
  plsa::io::Log in_us = log;
  in_us.source = "us.csv";
  in_us.data(1, 0) = 1.7e15;
  try {
    plsa::lcm::writeLcmLog(good, in_us);
    ADD_FAILURE() << "a time beyond int64 microseconds was written";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("row 2 of us.csv: time_s 1700000000000000.000000 s is beyond"),
              std::string::npos)
        << e.what();
  }
  in_us.data(1, 0) = 1e10;  // seconds, but past 2^53 us: read back, it would lose microseconds
  EXPECT_THROW(plsa::lcm::writeLcmLog(good, in_us), std::invalid_argument);
  plsa::lcm::writeLcmLog(good, log);
  {  // A utime near 2^62 written by another tool: named, not read as a rate that wanders by a millisecond.
    std::string bytes;
    {
      std::ifstream in(good, std::ios::binary);
      bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    const std::size_t utime_at = 28 + std::string("PLSA_STATE").size() + 8;  // header, channel, type hash
    for (int b = 0; b < 8; ++b) bytes[utime_at + static_cast<std::size_t>(b)] = b == 0 ? '\x40' : '\0';
    const std::string far = tempPath("far.lcmlog");
    std::ofstream(far, std::ios::binary) << bytes;
    try {
      plsa::lcm::readLcmLog(far);
      ADD_FAILURE() << "a utime of 2^62 us was read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("utime 4611686018427387904 us is beyond 2^53 us"), std::string::npos)
          << e.what();
    }
  }
  try {
    plsa::lcm::readLcmLog(good, "OTHER_CHANNEL");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no actuator-state messages on channel OTHER_CHANNEL"), std::string::npos);
  }
  // Cut the file mid-event (a recorder killed mid-write): the complete events read, and that is said.
  const auto size = fs::file_size(good);
  fs::resize_file(good, size - 10);
  const auto partial = plsa::lcm::readLcmLog(good);
  EXPECT_EQ(partial.samples(), 2);
  ASSERT_EQ(partial.warnings.size(), 1u);
  EXPECT_NE(partial.warnings[0].find("the log ends inside event 3"), std::string::npos) << partial.warnings[0];
  log.data(2, 0) = 0.01;  // time going backwards
  plsa::lcm::writeLcmLog(good, log);
  try {
    plsa::lcm::readLcmLog(good);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("event 3"), std::string::npos) << e.what();
  }
  fs::remove(junk);
  fs::remove(good);
}

// Lengths in the file are checked against limits and what is left before
// anything is allocated: an event data length of 0x7fffffff, or a logged
// message with a huge chamber count, crashed liblcm's reader.
TEST(LcmLog, HostileLengthsAreNamedErrorsAndLogsAreKnownByTheirMagicNumber) {
  plsa::io::Log log;
  log.columns = {"time_s", "cmd_1", "cmd_2", "cmd_3", "p_1", "p_2", "p_3", "bend_deg", "steer_deg"};
  log.data = Eigen::MatrixXd::Zero(2, 9);
  log.data.col(0) << 0.0125, 0.025;
  const std::string path = tempPath("lcmlog-2026-11-25.00");  // lcm-logger's default name: no extension
  plsa::lcm::writeLcmLog(path, log);
  EXPECT_TRUE(plsa::lcm::isLcmLog(path));
  EXPECT_EQ(plsa::lcm::readLogFile(path).samples(), 2);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  auto errorOf = [](const std::string& b) {
    std::istringstream in(b);
    try {
      plsa::lcm::readLcmLog(in, "x.lcmlog");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  auto patched = [&](std::size_t at, std::uint32_t v) {
    std::string b = bytes;
    for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<char>(v >> (24 - 8 * i));
    return b;
  };
  // Event header: sync word, event number, timestamp, channel length (byte 20), data length (byte 24).
  EXPECT_NE(errorOf(patched(24, 0x7FFFFFFFu)).find("event 1 (byte 0): data length 2147483647 is above"),
            std::string::npos);
  EXPECT_NE(errorOf(patched(24, 0xFFFFFFFFu)).find("data length -1 is negative"), std::string::npos);
  EXPECT_NE(errorOf(patched(20, 0x40000000u)).find("channel name length"), std::string::npos);
  // The message's own chamber count: after the header (28), the channel (10), its fingerprint, utime and seq (24).
  EXPECT_NE(errorOf(patched(28 + 10 + 24, 0x10000000u)).find("n_chambers = 268435456 is outside 0..16"),
            std::string::npos);
  EXPECT_NE(errorOf(patched(0, 0x12345678u)).find("no LCM sync word: not an LCM event log"), std::string::npos);
  fs::remove(path);
}

// The codec's format takes the placeholder's place in a registry (the one a
// build without LCM keeps): same name, rank and magic bytes, now readable and
// writable; registering it again changes nothing.
TEST(LcmLog, RegisteredFormatReplacesThePlaceholder) {
  plsa::io::LogReaderRegistry r;
  r.add(plsa::io::csvLogFormat());
  r.add(plsa::io::lcmLogPlaceholder());
  EXPECT_EQ(plsa::lcm::lcmLogFormat().magic, plsa::io::lcmLogPlaceholder().magic);
  plsa::lcm::registerLogFormats(r);
  plsa::lcm::registerLogFormats(r);
  EXPECT_EQ(r.names(), (std::vector<std::string>{"csv", "lcm"}));
  EXPECT_EQ(r.readable(), (std::vector<std::string>{"csv", "lcm"}));
  EXPECT_EQ(r.writable(), (std::vector<std::string>{"csv", "lcm"}));

  plsa::sim::ExperimentOptions o;
  o.joystick_duration_s = 2;
  plsa::sim::Actuator a(plsa::sim::SimConfig{}, 3);
  const plsa::io::Log log = plsa::sim::runExperiment(a, plsa::sim::joystickExperiment(o));
  const std::string path = tempPath("registry.lcmlog"), bare = tempPath("lcmlog-registry.00");
  plsa::io::WriteOptions wo;
  wo.lcm_channel = "OTHER";
  r.write(path, log, wo);  // by the extension
  EXPECT_TRUE(plsa::lcm::isLcmLog(path));
  fs::rename(path, bare);
  plsa::io::ReadOptions ro;
  ro.lcm_channel = "OTHER";
  EXPECT_EQ(r.read(bare, ro).samples(), log.samples());  // by the content
  ro.required = {"no_such_column"};
  EXPECT_THROW(r.read(bare, ro), std::runtime_error);
  fs::remove(bare);
}
