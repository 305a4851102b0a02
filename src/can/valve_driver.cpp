#include "plsa/can/valve_driver.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace plsa::can {

const char* toString(DriverFault f) {
  switch (f) {
    case DriverFault::kNone:
      return "no fault";
    case DriverFault::kStaleSensor:
      return "no valid pressure reading within the sensor timeout: vented";
    case DriverFault::kCommandTimeout:
      return "commands stopped for longer than the command timeout: vented";
    case DriverFault::kBusOff:
      return "CAN controller is bus-off: no frame can be sent, a vent frame neither; the valves rely on their own "
             "command timeout";
    case DriverFault::kErrorPassive:
      return "CAN controller is error-passive: vented";
    case DriverFault::kShutdown:
      return "shut down: vented";
    case DriverFault::kOverPressure:
      return "a chamber reads above the overpressure limit: vented";
  }
  return "unknown";
}

void checkSafetyLimits(const SignalMap& map, const SafetyLimits& limits) {
  // An infinite timeout or rate would switch that protection off.
  const std::pair<const char*, double> named[] = {{"max_pressure_bar", limits.max_pressure_bar},
                                                  {"max_rate_bar_per_s", limits.max_rate_bar_per_s},
                                                  {"sensor_timeout_s", limits.sensor_timeout_s},
                                                  {"command_timeout_s", limits.command_timeout_s},
                                                  {"overpressure_margin_bar", limits.overpressure_margin_bar}};
  for (const auto& [name, value] : named)
    if (!(value > 0) || !std::isfinite(value))
      throw std::invalid_argument(std::string("ValveDriver: safety limit ") + name + " is " + std::to_string(value) +
                                  "; every limit must be positive and finite");
  // A set-point the frame cannot carry is never sent: the valve would hold its last one instead.
  for (const Signal& sig : map.message("valve_command").signals) {
    MessageLayout one = map.message("valve_command");
    one.signals = {sig};
    CanFrame f;
    const double vent = 0.0, top = limits.max_pressure_bar;
    if (encodeFrame(one, &vent, 0, f) && encodeFrame(one, &top, 0, f)) continue;
    const PhysicalRange r = physicalRange(sig);
    std::ostringstream msg;
    msg << "ValveDriver: valve_command signal '" << sig.name << "' carries " << r.lo << " to " << r.hi
        << " bar; the vent (0) and the set-point clamp (" << top << " bar) must both fit it";
    throw std::invalid_argument(msg.str());
  }
}

ValveDriver::ValveDriver(CanTransport& transport, const SignalMap& map, const SafetyLimits& limits, double start_time_s)
    : transport_(transport),
      valve_(&map.message("valve_command")),
      sensor_(&map.message("pressure_sensor")),
      limits_(limits),
      last_sensor_(start_time_s),
      last_tick_(start_time_s) {
  if (valve_->signals.size() != 3 || sensor_->signals.size() != 3)
    throw std::invalid_argument("ValveDriver: valve_command and pressure_sensor need three signals each");
  tip_ = map.find("tip_angle");
  if (tip_ && tip_->signals.size() != 2)
    throw std::invalid_argument("ValveDriver: tip_angle needs two signals (bend, steer)");
  checkSafetyLimits(map, limits);
}

bool ValveDriver::command(double time_s, const std::array<double, 3>& setpoint) noexcept {
  for (double p : setpoint)
    if (!std::isfinite(p)) {
      ++counters_.rejected_commands;
      return false;
    }
  for (std::size_t i = 0; i < 3; ++i) setpoint_[i] = std::clamp(setpoint[i], 0.0, limits_.max_pressure_bar);
  last_command_ = time_s;
  have_command_ = true;
  return true;
}

void ValveDriver::latch(DriverFault f) noexcept {
  if (fault_ == DriverFault::kNone) fault_ = f;  // the first cause is the one reported
}

void ValveDriver::tick(double time_s) noexcept {
  CanFrame f;
  double values[MessageLayout::kMaxSignals];
  while (transport_.receive(f, std::chrono::microseconds(0)) == TransportStatus::kOk) {
    if (tip_ && f.id == tip_->id) {
      const DecodeStatus st = decodeFrame(*tip_, f, values, tip_counter_);
      if (st == DecodeStatus::kWrongLength) ++counters_.bad_length;
      if (st == DecodeStatus::kBadChecksum) ++counters_.bad_checksum;
      if (st == DecodeStatus::kOk || st == DecodeStatus::kCounterGap) {
        tip_angle_ = {values[0], values[1]};
        have_tip_ = true;
        ++counters_.tip_frames;
      }
      continue;
    }
    if (f.id != sensor_->id) {
      ++counters_.other_frames;
      continue;
    }
    const DecodeStatus st = decodeFrame(*sensor_, f, values, sensor_counter_);
    if (st == DecodeStatus::kWrongLength) {
      ++counters_.bad_length;
      continue;
    }
    if (st == DecodeStatus::kBadChecksum) {
      ++counters_.bad_checksum;
      continue;
    }
    if (st == DecodeStatus::kCounterGap) ++counters_.counter_gaps;  // the frame itself is good
    ++counters_.sensor_frames;
    for (std::size_t i = 0; i < 3; ++i) pressure_[i] = values[i];
    last_sensor_ = time_s;
    for (double p : pressure_)
      if (p > limits_.overpressureBar()) {
        ++counters_.overpressure_readings;
        latch(DriverFault::kOverPressure);
      }
  }
  switch (transport_.busState()) {
    case BusState::kBusOff:
      latch(DriverFault::kBusOff);
      break;
    case BusState::kErrorPassive:
      latch(DriverFault::kErrorPassive);
      break;
    case BusState::kActive:
      break;
  }
  if (time_s - last_sensor_ > limits_.sensor_timeout_s) latch(DriverFault::kStaleSensor);
  if (have_command_ && time_s - last_command_ > limits_.command_timeout_s) latch(DriverFault::kCommandTimeout);
  const double dt = std::max(0.0, time_s - last_tick_);
  last_tick_ = time_s;
  if (fault_ != DriverFault::kNone) {
    output_ = {0.0, 0.0, 0.0};  // vent at once, no ramp
  } else if (have_command_) {
    const double step = limits_.max_rate_bar_per_s * dt;
    for (std::size_t i = 0; i < 3; ++i) output_[i] += std::clamp(setpoint_[i] - output_[i], -step, step);
  }
  send();
}

bool ValveDriver::clearFault(double time_s) noexcept {
  if (fault_ == DriverFault::kNone) return true;
  const bool fresh_sensor = time_s - last_sensor_ <= limits_.sensor_timeout_s;
  const bool bus_ok = transport_.busState() == BusState::kActive;
  const bool commands_ok = !have_command_ || time_s - last_command_ <= limits_.command_timeout_s;
  bool pressure_ok = true;
  for (double p : pressure_) pressure_ok = pressure_ok && p <= limits_.overpressureBar();
  if (!fresh_sensor || !bus_ok || !commands_ok || !pressure_ok) return false;
  fault_ = DriverFault::kNone;
  output_ = {0.0, 0.0, 0.0};  // resume from vented, ramping under the rate limit
  return true;
}

void ValveDriver::shutdown(double time_s) noexcept {
  fault_ = DriverFault::kShutdown;
  output_ = {0.0, 0.0, 0.0};
  last_tick_ = time_s;
  send();
}

void ValveDriver::send() noexcept {
  CanFrame f;
  last_send_ok_ = false;
  if (!encodeFrame(*valve_, output_.data(), valve_counter_++, f)) {
    ++counters_.send_failures;
    return;
  }
  last_send_ok_ = transport_.send(f) == TransportStatus::kOk;
  if (last_send_ok_)
    ++counters_.valve_frames;
  else
    ++counters_.send_failures;
}

}  // namespace plsa::can
