#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "plsa/can/simulated_valve_device.hpp"
#include "plsa/can/valve_driver.hpp"
#include "plsa/testing/alloc_guard.hpp"

using namespace plsa::can;
using namespace std::chrono_literals;

namespace {

std::string errorOf(const std::string& json) {
  try {
    signalMapFromJson(json, "map.json");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "accepted";
}

const char* kOneMessage = R"({"profile": "t", "messages": [{"name": "m", "id": 256, "dlc": 8, "counter_byte": 6,
  "checksum_byte": 7, "signals": [%s]}]})";

std::string withSignals(const std::string& signals) {
  char buf[1024];
  std::snprintf(buf, sizeof buf, kOneMessage, signals.c_str());
  return buf;
}

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

TEST(SignalMap, DefaultProfileRoundTripsAndDetectsCorruption) {
  const SignalMap map = defaultSignalMap();
  const MessageLayout& m = map.message("pressure_sensor");
  const double in[3] = {0.1, 0.25, 0.39999};
  CanFrame f;
  ASSERT_TRUE(encodeFrame(m, in, 5, f));
  double out[8];
  int counter = 4;
  ASSERT_EQ(decodeFrame(m, f, out, counter), DecodeStatus::kOk);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(out[i], in[i], 5e-6);
  for (int byte = 0; byte < 8; ++byte) {
    CanFrame bad = f;
    bad.data[static_cast<std::size_t>(byte)] ^= 0x10;
    int c = 4;
    EXPECT_EQ(decodeFrame(m, bad, out, c), DecodeStatus::kBadChecksum) << "byte " << byte;
  }
  CanFrame short_frame = f;
  short_frame.dlc = 6;
  EXPECT_EQ(decodeFrame(m, short_frame, out, counter), DecodeStatus::kWrongLength);
  ASSERT_TRUE(encodeFrame(m, in, 7, f));  // counter 5 -> 7: one frame lost
  counter = 5;
  EXPECT_EQ(decodeFrame(m, f, out, counter), DecodeStatus::kCounterGap);
  const double too_big[3] = {0.9, 0.0, 0.0};  // 0.9 bar does not fit 16 bits at 1e-5
  EXPECT_FALSE(encodeFrame(m, too_big, 0, f));
  EXPECT_THROW(map.message("heater"), std::invalid_argument);
}

TEST(SignalMap, SignedBigEndianSignalsAndJsonErrors) {
  const SignalMap map = signalMapFromJson(withSignals(
      R"({"name": "a", "byte": 0, "bits": 16, "endian": "big", "signed": true, "scale": 0.01, "offset": 1.0},
         {"name": "b", "byte": 2, "bits": 32, "scale": 1.0})"));
  const double in[2] = {-3.21, 123456.0};
  CanFrame f;
  ASSERT_TRUE(encodeFrame(map.messages[0], in, 0, f));
  double out[8];
  int c = -1;
  ASSERT_EQ(decodeFrame(map.messages[0], f, out, c), DecodeStatus::kOk);
  EXPECT_NEAR(out[0], -3.21, 1e-9);
  EXPECT_EQ(out[1], 123456.0);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 5, "bits": 16, "scale": 1})")).find("overlaps"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 12, "scale": 1})")).find("8, 16 or 32"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 0})")).find("non-zero"),
            std::string::npos);
  EXPECT_NE(
      errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 1, "endian": "middle"})")).find("endian"),
      std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "t"})").find("map.json"), std::string::npos);
  EXPECT_NE(errorOf("{").find("not valid JSON"), std::string::npos);
  // Found by fuzz_signal_map: a number too large for a double is a JSON error too, not a crash.
  EXPECT_NE(errorOf("77.276e25776e257LF{").find("not valid JSON"), std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 8, "scale": 1e999})")).find("map.json"),
            std::string::npos);
  // Found by fuzz_signal_map under UBSan: a float too large for the id's
  // integer type was converted before any check. Integer fields are now
  // type- and range-checked first.
  EXPECT_NE(errorOf(R"({"profile": "p", "messages": [{"name": "m", "id": 2564444444444444444001722586, "dlc": 8,
    "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1}]}]})")
                .find("'id' must be an integer"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "p", "messages": [{"name": "m", "id": 256, "dlc": 8.5,
    "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1}]}]})")
                .find("'dlc' must be an integer"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": -3, "bits": 16, "scale": 1})")).find("'byte' must be in 0..7"),
            std::string::npos);
}

TEST(SignalMap, DecodingAllocatesNothing) {
  const SignalMap map = defaultSignalMap();
  const MessageLayout& m = map.message("pressure_sensor");
  CanFrame f;
  const double in[3] = {0.1, 0.2, 0.3};
  ASSERT_TRUE(encodeFrame(m, in, 0, f));
  double out[8];
  int c = -1;
  int ok = 0;
  plsa::testing::AllocGuard guard;
  for (int k = 0; k < 10000; ++k) {
    f.data[6] = static_cast<std::uint8_t>(k);
    ok += decodeFrame(m, f, out, c) == DecodeStatus::kBadChecksum ? 0 : 1;
  }
  EXPECT_EQ(guard.allocations(), 0u);
  EXPECT_EQ(ok, (10000 + 255) / 256);  // the checksum is right only where the counter byte is back at 0
}

TEST(InProcessBus, DeliversToOthersAndInjectsFaults) {
  auto bus = InProcessBus::create();
  auto a = bus->connect(), b = bus->connect(4);
  CanFrame f;
  f.id = 0x123;
  f.dlc = 2;
  f.data[0] = 0xAB;
  ASSERT_EQ(a->send(f), TransportStatus::kOk);
  CanFrame got;
  ASSERT_EQ(b->receive(got, 10ms), TransportStatus::kOk);
  EXPECT_EQ(got.data[0], 0xAB);
  EXPECT_EQ(a->receive(got, 1ms), TransportStatus::kTimeout);  // not its own
  for (int i = 0; i < 6; ++i) a->send(f);
  EXPECT_EQ(b->stats().overflows, 2u);
  while (b->receive(got, 0us) == TransportStatus::kOk) {}
  bus->setFaults({1.0, 0.0, 0us, 3});
  a->send(f);
  EXPECT_EQ(b->receive(got, 2ms), TransportStatus::kTimeout);
  EXPECT_EQ(b->stats().dropped, 1u);
  bus->setFaults({0.0, 1.0, 0us, 3});
  a->send(f);
  ASSERT_EQ(b->receive(got, 10ms), TransportStatus::kOk);
  EXPECT_NE(got.data, f.data);
  bus->setFaults({0.0, 0.0, 20ms, 3});
  a->send(f);
  EXPECT_EQ(b->receive(got, 2ms), TransportStatus::kTimeout);  // delayed, not lost
  EXPECT_EQ(b->receive(got, 100ms), TransportStatus::kOk);
  bus->setBusState(BusState::kBusOff);
  EXPECT_EQ(a->send(f), TransportStatus::kBusOff);
  f.dlc = 9;
  EXPECT_EQ(a->send(f), TransportStatus::kBadFrame);
}

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

TEST(SimulatedValveDevice, SensorSaturatesAtItsFullScaleInsteadOfFallingSilent) {
  auto bus = InProcessBus::create();
  auto driver_port = bus->connect(), device_port = bus->connect();
  SignalMap map = defaultSignalMap();
  for (auto& m : map.messages)
    if (m.name == "pressure_sensor")
      for (auto& s : m.signals) {
        s.bits = 8;  // 0 to 0.51 bar: a narrower sensor than the valves
        s.scale = 0.002;
      }
  map.validate();
  plsa::sim::SimConfig config;
  config.max_pressure_bar = 0.6;
  SafetyLimits limits;
  limits.max_pressure_bar = 0.6;
  ValveDriver driver(*driver_port, map, limits, 0.0);
  SimulatedValveDevice device(*device_port, map, config, 1);
  const double dt = 1.0 / device.sampleRateHz();
  for (int k = 1; k * dt <= 3.0; ++k) {
    driver.command(k * dt, {0.6, 0.2, 0.0});
    driver.tick(k * dt);
    device.step();
  }
  EXPECT_EQ(driver.fault(), DriverFault::kNone) << toString(driver.fault());
  EXPECT_NEAR(driver.pressures()[0], 0.51, 1e-9);  // full scale, while the chamber is near 0.6
  EXPECT_NEAR(driver.pressures()[1], 0.2, 0.03);
  EXPECT_GT(device.stats().saturated_readings, 0);
  EXPECT_EQ(device.stats().send_failures, 0);
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

// The valve controller's own watchdog: without valid valve frames for its
// timeout it vents, as when the process driving it is killed outright.
TEST(SimulatedValveDevice, VentsOnItsOwnAfterACommandSilence) {
  auto bus = InProcessBus::create();
  auto driver_port = bus->connect(), device_port = bus->connect();
  const SignalMap map = defaultSignalMap();
  ValveDriver driver(*driver_port, map, SafetyLimits{}, 0.0);
  SimulatedValveDevice device(*device_port, map, plsa::sim::SimConfig{}, 1);
  device.setCommandTimeout(0.25);
  EXPECT_THROW(device.setCommandTimeout(0.0), std::invalid_argument);
  const double dt = 1.0 / device.sampleRateHz();
  int k = 1;
  for (; k * dt <= 1.0; ++k) {
    driver.command(k * dt, {0.3, 0.0, 0.0});
    driver.tick(k * dt);
    device.step();
  }
  EXPECT_NEAR(device.setpoint()[0], 0.3, 1e-4);
  EXPECT_FALSE(device.ventedBySilence());
  // The driver dies: no more frames. 0.2 s later the valves still hold, 0.3 s later they have vented.
  const int dead = k;
  for (; (k - dead) * dt < 0.2; ++k) device.step();
  EXPECT_NEAR(device.setpoint()[0], 0.3, 1e-4);
  for (; (k - dead) * dt < 0.3; ++k) device.step();
  EXPECT_TRUE(device.ventedBySilence());
  EXPECT_EQ(device.setpoint(), (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(device.stats().silence_vents, 1);
}

// Profiles that let two messages share an id or a signal name are refused;
// what the driver cannot guard against (no counter or checksum, signals in
// another order or unit) is named in warnings.
TEST(SignalMap, RefusesAmbiguousProfilesAndWarnsOfUnguardedOnes) {
  const std::string two = R"({"profile": "t", "messages": [
    {"name": "valve_command", "id": 256, "dlc": 8, "signals": [{"name": "a", "byte": 0, "bits": 16, "scale": 1e-5}]},
    {"name": "pressure_sensor", "id": 256, "dlc": 8, "signals": [{"name": "b", "byte": 0, "bits": 16, "scale": 1e-5}]}]})";
  EXPECT_NE(errorOf(two).find("id 256 is also message 'valve_command's"), std::string::npos) << errorOf(two);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1},
                                   {"name": "a", "byte": 2, "bits": 16, "scale": 1})"))
                .find("signal 'a' is named twice"),
            std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1, "gain": 2})")).find("unknown key"),
            std::string::npos);
  EXPECT_NE(errorOf(R"({"profile": "t", "profile": "u", "messages": []})").find("given twice"), std::string::npos);
  EXPECT_NE(errorOf(withSignals(R"({"name": "a", "byte": 0, "bits": 16, "scale": 1e400})")).find("not valid JSON"),
            std::string::npos);

  EXPECT_TRUE(driverProfileWarnings(defaultSignalMap()).empty());
  SignalMap bare = defaultSignalMap();
  for (auto& m : bare.messages)
    if (m.name == "valve_command") {
      m.counter_byte = m.checksum_byte = -1;
      std::swap(m.signals[0].name, m.signals[1].name);
    }
  bare.validate();
  const std::vector<std::string> w = driverProfileWarnings(bare);
  ASSERT_EQ(w.size(), 3u);
  EXPECT_NE(w[0].find("no rolling counter"), std::string::npos) << w[0];
  EXPECT_NE(w[1].find("no checksum"), std::string::npos) << w[1];
  EXPECT_NE(w[2].find("taken by position, in this order: setpoint_2, setpoint_1, setpoint_3"), std::string::npos)
      << w[2];
}
