// The valve and pressure-sensor driver over a CAN transport, with the safety
// this device needs inside a body: set-points clamped and rate limited, a
// stale-sensor watchdog and a command timeout, bus-off / error-passive
// detection. Any fault vents every chamber and latches until cleared.
#pragma once

#include <array>
#include <cstdint>

#include "plsa/can/can_transport.hpp"
#include "plsa/can/signal_map.hpp"

namespace plsa::can {

struct SafetyLimits {
  double max_pressure_bar = 0.4;
  double max_rate_bar_per_s = 2.0;
  double sensor_timeout_s = 0.1;    ///< no valid reading for this long: fault
  double command_timeout_s = 0.25;  ///< commands stop for this long: fault
  /// A valid reading above max_pressure_bar + this is a fault (a failed valve
  /// or regulator, or a frame that is not what it claims): the clamp keeps
  /// set-points at max_pressure_bar, so nothing commanded reads above it.
  double overpressure_margin_bar = 0.1;
  double overpressureBar() const noexcept { return max_pressure_bar + overpressure_margin_bar; }
};

/// Throws std::invalid_argument unless every limit is positive and finite, and each
/// valve_command signal can carry both the vent (0) and the clamp: a set-point
/// a frame cannot encode is never sent, so the valve would hold its last one.
void checkSafetyLimits(const SignalMap& map, const SafetyLimits& limits);

enum class DriverFault { kNone, kStaleSensor, kCommandTimeout, kBusOff, kErrorPassive, kShutdown, kOverPressure };
const char* toString(DriverFault f);

struct DriverCounters {
  std::uint64_t sensor_frames = 0, bad_length = 0, bad_checksum = 0, counter_gaps = 0, other_frames = 0;
  std::uint64_t rejected_commands = 0, valve_frames = 0, send_failures = 0, tip_frames = 0;
  std::uint64_t overpressure_readings = 0;
};

/// Three chambers; the signal map must have "valve_command" and
/// "pressure_sensor" messages with three signals each, and may have a
/// "tip_angle" message (bend_deg, steer_deg) from the tip sensor. Time is passed in
/// (seconds, any monotonic clock), so the safety logic is testable. The
/// watchdogs act at tick(): tick at least twice per timeout, since a vent
/// comes up to two tick periods after the timeout it enforces.
/// command() and tick() never allocate or throw.
class ValveDriver {
 public:
  ValveDriver(CanTransport& transport, const SignalMap& map, const SafetyLimits& limits, double start_time_s);

  /// A new set-point per chamber (bar). Non-finite values are rejected (false).
  bool command(double time_s, const std::array<double, 3>& setpoint_bar) noexcept;
  /// Reads sensor frames, runs the watchdogs, sends the valve frame.
  void tick(double time_s) noexcept;
  /// Clears a latched fault if its cause is gone (fresh sensor data, bus
  /// active, commands fresh or none yet); returns whether it cleared.
  bool clearFault(double time_s) noexcept;
  /// Vents and latches kShutdown (clean shutdown, SIGINT/SIGTERM).
  void shutdown(double time_s) noexcept;

  DriverFault fault() const noexcept { return fault_; }
  const std::array<double, 3>& pressures() const noexcept { return pressure_; }
  const std::array<double, 3>& output() const noexcept { return output_; }  ///< last set-points sent
  /// Whether the last valve frame reached the transport: after a fault, whether
  /// the vent was actually sent (not on a bus-off controller).
  bool lastFrameSent() const noexcept { return last_send_ok_; }
  const DriverCounters& counters() const noexcept { return counters_; }
  /// Tip sensor (bend, steer in degrees) when the profile has it and a valid frame came.
  bool hasTipAngle() const noexcept { return have_tip_; }
  const std::array<double, 2>& tipAngle() const noexcept { return tip_angle_; }

 private:
  void latch(DriverFault f) noexcept;
  void send() noexcept;

  CanTransport& transport_;
  const MessageLayout* valve_;
  const MessageLayout* sensor_;
  const MessageLayout* tip_ = nullptr;
  std::array<double, 2> tip_angle_{};
  bool have_tip_ = false;
  int tip_counter_ = -1;
  SafetyLimits limits_;
  std::array<double, 3> setpoint_{}, output_{}, pressure_{};
  double last_sensor_ = 0.0, last_command_ = 0.0, last_tick_ = 0.0;
  bool have_command_ = false;
  int sensor_counter_ = -1;
  std::uint8_t valve_counter_ = 0;
  bool last_send_ok_ = false;
  DriverFault fault_ = DriverFault::kNone;
  DriverCounters counters_;
};

}  // namespace plsa::can
