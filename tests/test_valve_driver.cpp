// The valve driver: clamps and rate limits, the faults that vent, the limits it refuses (plsa/can/valve_driver.hpp).
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "plsa/can/valve_driver.hpp"

using namespace plsa::can;
using namespace std::chrono_literals;

namespace {

// A pressure sensor on the bus: sends readings with a rolling counter.
struct SensorNode {
  std::unique_ptr<CanTransport> port;
  const MessageLayout& layout;
  std::uint8_t counter = 0;
  void send(std::array<double, 3> p) {
    CanFrame f;
    ASSERT_TRUE(encodeFrame(layout, p.data(), counter++, f));
    ASSERT_EQ(port->send(f), TransportStatus::kOk);
  }
};

// What the valves were told, read back from the bus.
std::array<double, 3> lastValveFrame(CanTransport& port, const MessageLayout& valve) {
  std::array<double, 3> v{-1, -1, -1};
  CanFrame f;
  int counter = -1;
  double values[8];
  while (port.receive(f, 0us) == TransportStatus::kOk)
    if (f.id == valve.id && decodeFrame(valve, f, values, counter) != DecodeStatus::kBadChecksum)
      v = {values[0], values[1], values[2]};
  return v;
}

}  // namespace

class DriverTest : public ::testing::Test {
 protected:
  std::shared_ptr<InProcessBus> bus = InProcessBus::create();
  SignalMap map = defaultSignalMap();
  std::unique_ptr<CanTransport> driver_port = bus->connect(), valves = bus->connect();
  SensorNode sensor{bus->connect(), map.message("pressure_sensor")};
  SafetyLimits limits;
  ValveDriver driver{*driver_port, map, limits, 0.0};
  const MessageLayout& valve = map.message("valve_command");

  // One 10 ms tick with a fresh reading and (optionally) a command.
  std::array<double, 3> tick(double t, const std::array<double, 3>* cmd) {
    sensor.send({0.1, 0.1, 0.1});
    if (cmd) driver.command(t, *cmd);
    driver.tick(t);
    return lastValveFrame(*valves, valve);
  }
};

TEST_F(DriverTest, ClampsAndRateLimitsSetPoints) {
  const std::array<double, 3> cmd{0.9, 0.1, -0.5};
  auto out = tick(0.01, &cmd);
  EXPECT_NEAR(out[0], 0.02, 1e-5);  // 2 bar/s for 10 ms
  EXPECT_NEAR(out[2], 0.0, 1e-9);
  for (int k = 2; k <= 40; ++k) out = tick(0.01 * k, &cmd);
  EXPECT_NEAR(out[0], 0.4, 1e-5);  // clamped to the maximum
  EXPECT_NEAR(out[1], 0.1, 1e-5);
  EXPECT_EQ(driver.fault(), DriverFault::kNone);
  EXPECT_NEAR(driver.pressures()[0], 0.1, 1e-5);
  EXPECT_FALSE(driver.command(0.41, {std::nan(""), 0, 0}));
  EXPECT_EQ(driver.counters().rejected_commands, 1u);
}

TEST_F(DriverTest, StaleSensorVentsAndLatchesUntilCleared) {
  const std::array<double, 3> cmd{0.3, 0.3, 0.3};
  for (int k = 1; k <= 30; ++k) tick(0.01 * k, &cmd);
  // The sensor falls silent: within the timeout the driver vents.
  for (int k = 31; k <= 45; ++k) {
    driver.command(0.01 * k, cmd);
    driver.tick(0.01 * k);
  }
  EXPECT_EQ(driver.fault(), DriverFault::kStaleSensor);
  EXPECT_EQ(lastValveFrame(*valves, valve), (std::array<double, 3>{0, 0, 0}));
  // Readings return: still vented until explicitly cleared.
  auto out = tick(0.46, &cmd);
  EXPECT_EQ(driver.fault(), DriverFault::kStaleSensor);
  EXPECT_EQ(out, (std::array<double, 3>{0, 0, 0}));
  EXPECT_TRUE(driver.clearFault(0.46));
  out = tick(0.47, &cmd);
  EXPECT_NEAR(out[0], 0.02, 1e-5);  // ramps up again under the rate limit
  EXPECT_STREQ(toString(DriverFault::kStaleSensor), "no valid pressure reading within the sensor timeout: vented");
}

TEST_F(DriverTest, CommandTimeoutVentsAndCannotBeClearedWhileStale) {
  const std::array<double, 3> cmd{0.2, 0, 0};
  for (int k = 1; k <= 20; ++k) tick(0.01 * k, &cmd);
  std::array<double, 3> out{};
  for (int k = 21; k <= 50; ++k) out = tick(0.01 * k, nullptr);  // commands stop
  EXPECT_EQ(driver.fault(), DriverFault::kCommandTimeout);
  EXPECT_EQ(out, (std::array<double, 3>{0, 0, 0}));
  EXPECT_FALSE(driver.clearFault(0.5));  // commands are still stale
  driver.command(0.5, cmd);
  EXPECT_TRUE(driver.clearFault(0.5));
}

TEST_F(DriverTest, BusOffAndErrorPassiveVentWithTheirReason) {
  const std::array<double, 3> cmd{0.2, 0, 0};
  for (int k = 1; k <= 10; ++k) tick(0.01 * k, &cmd);
  bus->setBusState(BusState::kErrorPassive);
  tick(0.11, &cmd);
  EXPECT_EQ(driver.fault(), DriverFault::kErrorPassive);
  EXPECT_FALSE(driver.clearFault(0.11));
  bus->setBusState(BusState::kActive);
  EXPECT_TRUE(driver.clearFault(0.11));
  bus->setBusState(BusState::kBusOff);
  driver.tick(0.12);
  EXPECT_EQ(driver.fault(), DriverFault::kBusOff);
  EXPECT_GE(driver.counters().send_failures, 1u);
}

TEST_F(DriverTest, CorruptSensorFramesAreCountedNotUsed) {
  const std::array<double, 3> cmd{0.2, 0, 0};
  tick(0.01, &cmd);
  bus->setFaults({0.0, 1.0, 0us, 9});
  for (int k = 2; k <= 20; ++k) tick(0.01 * k, &cmd);
  EXPECT_GT(driver.counters().bad_checksum, 10u);
  EXPECT_EQ(driver.fault(), DriverFault::kStaleSensor);  // no valid reading for 0.19 s
}

TEST_F(DriverTest, ShutdownVents) {
  const std::array<double, 3> cmd{0.3, 0.3, 0};
  for (int k = 1; k <= 30; ++k) tick(0.01 * k, &cmd);
  driver.shutdown(0.31);
  EXPECT_EQ(driver.fault(), DriverFault::kShutdown);
  EXPECT_EQ(lastValveFrame(*valves, valve), (std::array<double, 3>{0, 0, 0}));
}

TEST(ValveDriverSetup, RefusesAClampTheSetPointSignalCannotCarry) {
  auto bus = InProcessBus::create();
  auto port = bus->connect();
  const SignalMap map = defaultSignalMap();  // 16-bit unsigned at 1e-5 bar: 0 to 0.65535 bar
  SafetyLimits limits;
  limits.max_pressure_bar = 5.0;
  try {
    ValveDriver d(*port, map, limits, 0.0);
    FAIL() << "a 5 bar clamp was accepted on a 0.65535 bar set-point signal";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'setpoint_1'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("carries 0 to 0.65535 bar"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("clamp (5 bar)"), std::string::npos) << e.what();
  }
  limits.max_pressure_bar = 0.65;
  EXPECT_NO_THROW(ValveDriver(*port, map, limits, 0.0));
  // An infinite timeout or rate would switch that protection off.
  for (double SafetyLimits::*field :
       {&SafetyLimits::max_rate_bar_per_s, &SafetyLimits::sensor_timeout_s, &SafetyLimits::command_timeout_s}) {
    SafetyLimits off;
    off.*field = std::numeric_limits<double>::infinity();
    try {
      ValveDriver d(*port, map, off, 0.0);
      ADD_FAILURE() << "an infinite safety limit was accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("is inf; every limit must be positive and finite"), std::string::npos)
          << e.what();
    }
    off.*field = -1.0;
    EXPECT_THROW(ValveDriver(*port, map, off, 0.0), std::invalid_argument);
  }
  // A signal whose range leaves out zero cannot vent.
  SignalMap shifted = map;
  for (auto& m : shifted.messages)
    if (m.name == "valve_command") m.signals[1].offset = 0.1;
  limits.max_pressure_bar = 0.4;
  try {
    ValveDriver d(*port, shifted, limits, 0.0);
    FAIL() << "a set-point signal without 0 in its range was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'setpoint_2'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("the vent (0)"), std::string::npos) << e.what();
  }
}

// A reading above the clamp plus the margin is a fault whatever sent it (a
// failed regulator, or a frame that is not what it claims): the driver vents
// and will not clear while it persists.
TEST_F(DriverTest, OverpressureReadingVentsAndLatches) {
  const std::array<double, 3> cmd{0.3, 0.0, 0.0};
  for (int k = 1; k <= 30; ++k) tick(0.01 * k, &cmd);
  ASSERT_EQ(driver.fault(), DriverFault::kNone);
  sensor.send({0.6, 0.1, 0.1});  // spoofed: 0.6 bar, above 0.4 + 0.1
  driver.command(0.31, cmd);
  driver.tick(0.31);
  EXPECT_EQ(driver.fault(), DriverFault::kOverPressure);
  EXPECT_EQ(lastValveFrame(*valves, valve), (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(driver.counters().overpressure_readings, 1u);
  EXPECT_FALSE(driver.clearFault(0.31)) << "cleared while the last reading is still above the limit";
  auto out = tick(0.32, &cmd);  // readings back to 0.1 bar
  EXPECT_EQ(out, (std::array<double, 3>{0, 0, 0}));
  EXPECT_TRUE(driver.clearFault(0.32));
  // Just under the limit is no fault.
  for (int k = 33; k <= 40; ++k) tick(0.01 * k, &cmd);
  sensor.send({0.499, 0.1, 0.1});
  driver.tick(0.41);
  EXPECT_EQ(driver.fault(), DriverFault::kNone);
}

// On a bus-off controller nothing goes out: the driver does not claim a vent.
TEST_F(DriverTest, BusOffSaysNoVentFrameCouldBeSent) {
  const std::array<double, 3> cmd{0.2, 0, 0};
  for (int k = 1; k <= 10; ++k) tick(0.01 * k, &cmd);
  EXPECT_TRUE(driver.lastFrameSent());
  bus->setBusState(BusState::kBusOff);
  driver.tick(0.11);
  EXPECT_EQ(driver.fault(), DriverFault::kBusOff);
  EXPECT_FALSE(driver.lastFrameSent());
  EXPECT_NE(std::string(toString(DriverFault::kBusOff)).find("a vent frame neither"), std::string::npos);
  EXPECT_EQ(std::string(toString(DriverFault::kBusOff)).find(": vented"), std::string::npos);
}
