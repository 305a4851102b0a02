#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
  plsa::lcm::writeLcmLog(good, log);
  try {
    plsa::lcm::readLcmLog(good, "OTHER_CHANNEL");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no actuator-state messages on channel OTHER_CHANNEL"), std::string::npos);
  }
  // Cut the file mid-event: the complete events still read, or it fails clearly.
  const auto size = fs::file_size(good);
  fs::resize_file(good, size - 10);
  try {
    const auto partial = plsa::lcm::readLcmLog(good);
    EXPECT_EQ(partial.samples(), 2);
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(good), std::string::npos);
  }
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
