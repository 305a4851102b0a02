// The CAN-to-LCM bridge: pressure commands from LCM go to the valves through
// the safety driver; sensor frames come back as actuator-state messages,
// with status messages on faults and once a second. Stopping it vents.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "plsa/can/can_transport.hpp"
#include "plsa/can/signal_map.hpp"
#include "plsa/can/valve_driver.hpp"

namespace plsa::lcm {

struct CanBridgeOptions {
  std::string url;  ///< "" = LCM's default (LCM_DEFAULT_URL)
  can::SafetyLimits limits;
  double rate_hz = 80.0;    ///< driver ticks and state messages per second
  double duration_s = 0.0;  ///< 0: until stopped
  std::string command_channel = "PLSA_COMMAND";
  std::string state_channel = "PLSA_STATE";
  std::string status_channel = "PLSA_STATUS";
  std::string clear_channel = "PLSA_CLEAR_FAULT";  ///< any message here asks to clear a latched fault
};

/// One valve frame goes out per tick; above this rate they alone would take
/// over an eighth of a 1 Mbit/s bus, for a device whose pneumatics settle in tens of ms.
inline constexpr double kMaxCanBridgeRateHz = 1000.0;

/// Throws std::invalid_argument naming the option at fault: a rate outside
/// (0, kMaxCanBridgeRateHz], a rate below two ticks per sensor or command
/// timeout (the watchdogs act at ticks, so a vent comes at most two ticks
/// after its timeout), or safety limits the profile cannot carry
/// (can::checkSafetyLimits). Call it before opening the bus.
void checkCanBridgeOptions(const CanBridgeOptions& options, const can::SignalMap& map);

struct CanBridgeStats {
  std::int64_t states = 0, commands = 0, rejected_commands = 0, faults = 0;
  can::DriverFault last_fault = can::DriverFault::kNone;
};

/// Runs until `stop` is set or the duration passes; always leaves the
/// chambers vented (driver shutdown) before it returns. Throws
/// std::invalid_argument for bad options (checkCanBridgeOptions) and
/// std::runtime_error if LCM cannot be set up.
CanBridgeStats runCanBridge(const CanBridgeOptions& options, can::CanTransport& transport, const can::SignalMap& map,
                            const std::atomic<bool>& stop);

}  // namespace plsa::lcm
