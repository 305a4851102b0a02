#include "plsa/lcm/can_bridge.hpp"

#include <poll.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

namespace plsa::lcm {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t wallUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

class CanBridge {
 public:
  CanBridge(const CanBridgeOptions& o, can::CanTransport& t, const can::SignalMap& map, const std::atomic<bool>& stop)
      : o_(o), transport_(t), stop_(stop), lcm_(o.url), start_(Clock::now()), driver_(t, map, o.limits, 0.0) {
    if (!lcm_.good()) throw std::runtime_error("plsa can-bridge: cannot open LCM at '" + (o.url.empty() ? "default" : o.url) + "'");
    lcm_.subscribe(o.command_channel, &CanBridge::onCommand, this);
    lcm_.subscribeFunction(o.clear_channel, &CanBridge::onClear, this);
  }

  CanBridgeStats run() {
    publishStatus(plsa_lcm::status_t::VENTED, "started; chambers vented until the first command");
    const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o_.rate_hz));
    auto next = Clock::now();
    auto last_status = Clock::now();
    while (!stop_.load() && !(o_.duration_s > 0 && now() >= o_.duration_s)) {
      next += period;
      pump(next);
      driver_.tick(now());
      if (driver_.fault() != reported_) {
        reported_ = driver_.fault();
        if (reported_ != can::DriverFault::kNone) {
          ++stats_.faults;
          stats_.last_fault = reported_;
          publishStatus(plsa_lcm::status_t::FAULT, can::toString(reported_));
        }
      }
      publishState();
      if (Clock::now() - last_status >= std::chrono::seconds(1)) {
        publishStatus(driver_.fault() == can::DriverFault::kNone ? plsa_lcm::status_t::OK : plsa_lcm::status_t::FAULT,
                      driver_.fault() == can::DriverFault::kNone ? "running" : can::toString(driver_.fault()));
        last_status = Clock::now();
      }
    }
    driver_.shutdown(now());
    publishState();
    publishStatus(plsa_lcm::status_t::STOPPED, "stopped; vent frame sent to every chamber");
    return stats_;
  }

 private:
  double now() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

  void pump(Clock::time_point deadline) {
    const int fd = lcm_.getFileno();
    while (!stop_.load()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      pollfd pfd{fd, POLLIN, 0};
      if (::poll(&pfd, 1, static_cast<int>(std::max<long long>(0, left))) > 0) {
        lcm_.handle();
        continue;
      }
      if (left <= 0) return;
    }
  }

  void onCommand(const ::lcm::ReceiveBuffer*, const std::string&, const plsa_lcm::pressure_command_t* m) {
    std::array<double, 3> p{};
    bool ok = m->n_chambers == 3 && m->pressure_bar.size() == 3;
    for (std::size_t i = 0; ok && i < 3; ++i) p[i] = m->pressure_bar[i];
    if (!ok || !driver_.command(now(), p)) {
      ++stats_.rejected_commands;
      publishStatus(plsa_lcm::status_t::OK, "rejected a command: need 3 finite chamber pressures");
      return;
    }
    ++stats_.commands;
  }

  static void onClear(const ::lcm::ReceiveBuffer*, const std::string&, CanBridge* self) {
    if (self->driver_.fault() == can::DriverFault::kNone) return;
    const std::string why = can::toString(self->driver_.fault());
    if (self->driver_.clearFault(self->now())) {
      self->reported_ = can::DriverFault::kNone;
      self->publishStatus(plsa_lcm::status_t::OK, "fault cleared (was: " + why + ")");
    } else {
      self->publishStatus(plsa_lcm::status_t::FAULT, "fault not cleared, its cause remains: " + why);
    }
  }

  void publishState() {
    plsa_lcm::actuator_state_t m;
    m.utime = wallUs();
    m.seq = stats_.states++;
    m.n_chambers = 3;
    m.command_bar.assign(driver_.output().begin(), driver_.output().end());
    m.pressure_bar.assign(driver_.pressures().begin(), driver_.pressures().end());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.bend_deg = driver_.hasTipAngle() ? driver_.tipAngle()[0] : nan;
    m.steer_deg = driver_.hasTipAngle() ? driver_.tipAngle()[1] : nan;
    for (auto& row : m.sensor_rotation)
      for (double& v : row) v = nan;  // the bus carries angles, not the rotation
    m.vented = driver_.fault() != can::DriverFault::kNone ? 1 : 0;
    lcm_.publish(o_.state_channel, &m);
  }

  void publishStatus(int8_t state, const std::string& message) {
    const can::DriverCounters& c = driver_.counters();
    const can::TransportStats t = transport_.stats();
    plsa_lcm::status_t s;
    s.utime = wallUs();
    s.source = "plsa can-bridge";
    s.state = state;
    s.message = message;
    s.names = {"sensor_frames", "tip_frames",      "bad_length",   "bad_checksum",    "counter_gaps",
               "valve_frames",  "send_failures",   "commands",     "rejected_commands", "rx_overflows",
               "back_pressure", "malformed_frames", "bus_state",   "faults"};
    s.values = {static_cast<double>(c.sensor_frames), static_cast<double>(c.tip_frames),
                static_cast<double>(c.bad_length),    static_cast<double>(c.bad_checksum),
                static_cast<double>(c.counter_gaps),  static_cast<double>(c.valve_frames),
                static_cast<double>(c.send_failures), static_cast<double>(stats_.commands),
                static_cast<double>(stats_.rejected_commands), static_cast<double>(t.overflows),
                static_cast<double>(t.back_pressure), static_cast<double>(t.malformed),
                static_cast<double>(transport_.busState()), static_cast<double>(stats_.faults)};
    s.n_values = static_cast<int32_t>(s.names.size());
    lcm_.publish(o_.status_channel, &s);
  }

  CanBridgeOptions o_;
  can::CanTransport& transport_;
  const std::atomic<bool>& stop_;
  ::lcm::LCM lcm_;
  Clock::time_point start_;
  can::ValveDriver driver_;
  can::DriverFault reported_ = can::DriverFault::kNone;
  CanBridgeStats stats_;
};

}  // namespace

void checkCanBridgeOptions(const CanBridgeOptions& o, const can::SignalMap& map) {
  if (!(o.rate_hz > 0 && o.rate_hz <= kMaxCanBridgeRateHz)) {
    std::ostringstream msg;
    msg << "plsa can-bridge: --rate " << o.rate_hz << " Hz is outside (0, " << kMaxCanBridgeRateHz << "] Hz";
    throw std::invalid_argument(msg.str());
  }
  // The watchdogs act only at ticks: a vent comes up to two ticks after its timeout.
  const double timeout = std::min(o.limits.sensor_timeout_s, o.limits.command_timeout_s);
  if (timeout > 0 && o.rate_hz * timeout < 2.0) {
    std::ostringstream msg;
    msg << "plsa can-bridge: --rate " << o.rate_hz << " Hz ticks every " << 1.0 / o.rate_hz << " s, but the "
        << (o.limits.sensor_timeout_s <= o.limits.command_timeout_s ? "--sensor-timeout" : "--command-timeout")
        << " of "
        << timeout << " s needs a tick at least every " << timeout / 2 << " s (--rate " << 2.0 / timeout
        << " or more) to vent in time";
    throw std::invalid_argument(msg.str());
  }
  try {
    can::checkSafetyLimits(map, o.limits);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("plsa can-bridge: profile '" + map.profile + "': " + e.what());
  }
}

CanBridgeStats runCanBridge(const CanBridgeOptions& options, can::CanTransport& transport, const can::SignalMap& map,
                            const std::atomic<bool>& stop) {
  checkCanBridgeOptions(options, map);
  CanBridge bridge(options, transport, map, stop);
  return bridge.run();
}

}  // namespace plsa::lcm
