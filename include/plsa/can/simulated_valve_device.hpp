// The simulated actuator behind the CAN protocol: it reads valve set-point
// frames, steps the actuator, and answers with pressure-sensor (and tip
// angle) frames, as the hardware would. Lets the driver, the bridge and
// their safety be tested end to end without a device.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>

#include "plsa/can/can_transport.hpp"
#include "plsa/can/signal_map.hpp"
#include "plsa/sim/actuator.hpp"

namespace plsa::can {

struct SimulatedDeviceStats {
  std::int64_t samples = 0, valve_frames = 0, bad_valve_frames = 0, frames_sent = 0, send_failures = 0;
  std::int64_t saturated_readings = 0;  ///< values sent at the signal's full scale (sensor saturation)
  std::int64_t silence_vents = 0;       ///< times the device vented on its own after a command silence
};

/// How long a valve controller holds its last set-point without a valid valve
/// frame before it vents on its own, as hardware controllers do: what keeps
/// the chambers safe when the process driving them is killed outright.
inline constexpr double kDefaultDeviceCommandTimeoutS = 0.5;

class SimulatedValveDevice {
 public:
  /// The map needs valve_command and pressure_sensor (three signals each);
  /// a tip_angle message, if present, is sent too. Throws std::invalid_argument.
  SimulatedValveDevice(CanTransport& transport, const SignalMap& map, const sim::SimConfig& config, std::uint64_t seed);

  /// One sample: takes the valve frames that arrived, steps the actuator
  /// with the latest valid set-points (valves hold their last set-point for
  /// up to the command timeout, then vent), sends the sensor frames,
  /// saturating readings at each signal's range.
  sim::ActuatorSample step();

  /// Seconds without a valid valve frame after which the valves vent on their
  /// own (default kDefaultDeviceCommandTimeoutS); throws std::invalid_argument
  /// unless positive and finite.
  void setCommandTimeout(double seconds);
  /// Whether the valves are vented because commands fell silent.
  bool ventedBySilence() const noexcept { return silent_; }

  const std::array<double, 3>& setpoint() const noexcept { return setpoint_; }
  const SimulatedDeviceStats& stats() const noexcept { return stats_; }
  double sampleRateHz() const noexcept { return actuator_.config().sample_rate_hz; }

 private:
  void sendMessage(const MessageLayout& m, const double* values, std::uint8_t& counter);

  CanTransport& transport_;
  const MessageLayout* valve_;
  const MessageLayout* sensor_;
  const MessageLayout* tip_ = nullptr;
  sim::Actuator actuator_;
  std::array<double, 3> setpoint_{};
  int valve_counter_ = -1;
  double command_timeout_s_ = kDefaultDeviceCommandTimeoutS;
  std::int64_t samples_since_command_ = 0;
  bool silent_ = true;  // vented until the first valid frame
  std::uint8_t sensor_counter_ = 0, tip_counter_ = 0;
  SimulatedDeviceStats stats_;
};

/// Runs the device in real time (absolute deadlines at the sample rate)
/// until `stop` is set or `duration_s` simulated seconds pass (0: no limit);
/// `on_sample` sees each sample (for a ground-truth publisher).
SimulatedDeviceStats runSimulatedDevice(SimulatedValveDevice& device, const std::atomic<bool>& stop, double duration_s,
                                        const std::function<void(const sim::ActuatorSample&)>& on_sample);

}  // namespace plsa::can
