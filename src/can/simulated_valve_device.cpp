#include "plsa/can/simulated_valve_device.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

namespace plsa::can {

SimulatedValveDevice::SimulatedValveDevice(CanTransport& transport, const SignalMap& map, const sim::SimConfig& config,
                                           std::uint64_t seed)
    : transport_(transport),
      valve_(&map.message("valve_command")),
      sensor_(&map.message("pressure_sensor")),
      actuator_(config, seed) {
  if (valve_->signals.size() != 3 || sensor_->signals.size() != 3)
    throw std::invalid_argument("simulated device: valve_command and pressure_sensor need three signals each");
  tip_ = map.find("tip_angle");
  if (tip_ && tip_->signals.size() != 2)
    throw std::invalid_argument("simulated device: tip_angle needs two signals (bend, steer)");
}

void SimulatedValveDevice::setCommandTimeout(double seconds) {
  if (!(seconds > 0) || !std::isfinite(seconds))
    throw std::invalid_argument("simulated device: the command timeout must be positive and finite");
  command_timeout_s_ = seconds;
}

void SimulatedValveDevice::sendMessage(const MessageLayout& m, const double* values, std::uint8_t& counter) {
  // A sensor reads full scale beyond its range; it does not fall silent.
  double sent[MessageLayout::kMaxSignals];
  for (std::size_t k = 0; k < m.signals.size(); ++k) {
    const PhysicalRange r = physicalRange(m.signals[k]);
    sent[k] = std::clamp(values[k], r.lo, r.hi);
    if (std::isfinite(values[k]) && sent[k] != values[k]) ++stats_.saturated_readings;
  }
  CanFrame f;
  if (encodeFrame(m, sent, counter++, f) && transport_.send(f) == TransportStatus::kOk)
    ++stats_.frames_sent;
  else
    ++stats_.send_failures;
}

sim::ActuatorSample SimulatedValveDevice::step() {
  CanFrame f;
  double values[MessageLayout::kMaxSignals];
  while (transport_.receive(f, std::chrono::microseconds(0)) == TransportStatus::kOk) {
    if (f.id != valve_->id) continue;
    const DecodeStatus st = decodeFrame(*valve_, f, values, valve_counter_);
    if (st != DecodeStatus::kOk && st != DecodeStatus::kCounterGap) {
      ++stats_.bad_valve_frames;  // a corrupted set-point is never applied
      continue;
    }
    ++stats_.valve_frames;
    for (std::size_t i = 0; i < 3; ++i) setpoint_[i] = values[i];
    samples_since_command_ = 0;
    silent_ = false;
  }
  // The controller's own watchdog: silence beyond the timeout vents, whatever came last.
  const double silence = static_cast<double>(samples_since_command_++) / actuator_.config().sample_rate_hz;
  if (!silent_ && silence > command_timeout_s_) {
    silent_ = true;
    ++stats_.silence_vents;
  }
  if (silent_) setpoint_ = {0.0, 0.0, 0.0};
  const sim::ActuatorSample s = actuator_.step(setpoint_);
  double p[3];
  for (std::size_t i = 0; i < 3; ++i) p[i] = std::max(0.0, s.pressure_bar[i]);  // gauge sensors read no vacuum
  sendMessage(*sensor_, p, sensor_counter_);
  if (tip_) {
    const double a[2] = {s.bend_deg, s.steer_deg};
    sendMessage(*tip_, a, tip_counter_);
  }
  ++stats_.samples;
  return s;
}

SimulatedDeviceStats runSimulatedDevice(SimulatedValveDevice& device, const std::atomic<bool>& stop, double duration_s,
                                        const std::function<void(const sim::ActuatorSample&)>& on_sample) {
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / device.sampleRateHz()));
  auto next = Clock::now();
  while (!stop.load()) {
    next += period;
    std::this_thread::sleep_until(next);
    const sim::ActuatorSample s = device.step();
    if (on_sample) on_sample(s);
    if (duration_s > 0 && s.time_s >= duration_s - 1e-9) break;
  }
  return device.stats();
}

}  // namespace plsa::can
