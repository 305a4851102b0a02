// The simulated actuator as an LCM node: takes pressure commands, publishes
// actuator state (80 Hz real time, or one state per command in lock-step) and
// vents every chamber when commands stop for longer than a timeout.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "plsa/can/can_transport.hpp"
#include "plsa/can/signal_map.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::lcm {

struct SimNodeOptions {
  std::string url;  ///< "" = LCM's default (LCM_DEFAULT_URL)
  sim::SimConfig config;
  std::uint64_t seed = 1;
  bool lockstep = false;
  double command_timeout_s = 0.5;
  double duration_s = 0.0;  ///< simulated seconds to run; 0 = until stopped
  std::string command_channel = "PLSA_COMMAND";
  std::string state_channel = "PLSA_STATE";
  std::string status_channel = "PLSA_STATUS";
};

/// Counts of what the node did, for its status messages and its exit report.
struct SimNodeStats {
  std::int64_t states_published = 0;
  std::int64_t commands_accepted = 0;
  std::int64_t commands_rejected = 0;
  std::int64_t vent_events = 0;
  std::int64_t sensor_frames_lost = 0;  ///< behind CAN: sensor frames that could not be sent
  std::int64_t saturated_readings = 0;  ///< behind CAN: readings sent at the signal's full scale
};

/// Runs until `stop` is set or the duration is reached; vents before it returns.
/// Throws std::runtime_error if LCM cannot be set up.
SimNodeStats runSimNode(const SimNodeOptions& options, const std::atomic<bool>& stop);

/// The simulated actuator behind the CAN protocol (valve frames in, sensor
/// frames out) in real time; its true state is published on the state
/// channel for observers (it takes no LCM commands). Throws like runSimNode.
SimNodeStats runSimCanNode(const SimNodeOptions& options, can::CanTransport& transport, const can::SignalMap& map,
                           const std::atomic<bool>& stop);

}  // namespace plsa::lcm
