// The simulated valves and pressure sensor: a saturating sensor, a watchdog of their own (simulated_valve_device.hpp).
#include <gtest/gtest.h>

#include <array>
#include <stdexcept>

#include "plsa/can/simulated_valve_device.hpp"
#include "plsa/can/valve_driver.hpp"
#include "plsa/sim/sim_config.hpp"

using namespace plsa::can;

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
