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

#include "plsa/lcm/message_codec.hpp"
#include "plsa/lcm/state_codec.hpp"

namespace plsa::lcm {
namespace {

using Clock = std::chrono::steady_clock;

class CanBridge {
 public:
  CanBridge(const CanBridgeOptions& o, can::CanTransport& t, const can::SignalMap& map, const std::atomic<bool>& stop)
      : o_(o), transport_(t), stop_(stop), lcm_(o.url), start_(Clock::now()), driver_(t, map, o.limits, 0.0) {
    // Vent first: valves left holding by an earlier bridge that was killed start safe.
    driver_.tick(now());
    if (!lcm_.good()) {
      driver_.shutdown(now());
      throw std::runtime_error("plsa can-bridge: cannot open LCM at '" + (o.url.empty() ? "default" : o.url) + "'");
    }
    lcm_.subscribe(o.command_channel, &CanBridge::onCommand, this);
    lcm_.subscribe(o.clear_channel, &CanBridge::onClear, this);
  }

  // Whatever ends the bridge, a vent frame goes out first.
  ~CanBridge() {
    if (!vented_on_exit_) driver_.shutdown(now());
  }
  CanBridge(const CanBridge&) = delete;
  CanBridge& operator=(const CanBridge&) = delete;

  CanBridgeStats run() {
    try {
      loop();
    } catch (const std::exception& e) {
      ventOnExit(std::string("stopped by an error: ") + e.what());
      throw;
    } catch (...) {
      ventOnExit("stopped by an unknown error");
      throw;
    }
    ventOnExit("stopped");
    return stats_;
  }

 private:
  void ventOnExit(const std::string& why) noexcept {
    driver_.shutdown(now());
    vented_on_exit_ = true;
    try {
      publishState();
      publishStatus(plsa_lcm::status_t::STOPPED, driver_.lastFrameSent()
                                                     ? why + "; vent frame sent to every chamber"
                                                     : why +
                                                           "; the vent frame could NOT be sent (bus-off or transport "
                                                           "failure): the valves rely on their own command timeout");
    } catch (...) {  // the vent frame is out; a report that cannot be sent changes nothing
    }
  }

  void loop() {
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
  }

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

  // Raw bytes: decoded by the checked decoder, never by lcm-gen's alone.
  void onCommand(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    std::string why = decodeMessage(rbuf->data, rbuf->data_size, command_);
    std::array<double, 3> p{};
    if (why.empty() && command_.n_chambers != 3)
      why = "n_chambers = " + std::to_string(command_.n_chambers) + ", this actuator has 3";
    for (std::size_t i = 0; why.empty() && i < 3; ++i) p[i] = command_.pressure_bar[i];
    if (why.empty() && !driver_.command(now(), p)) why = "a chamber pressure is NaN or Inf";
    if (!why.empty()) {
      ++stats_.rejected_commands;
      reportRejection("rejected a command on " + channel + ": " + why);
      return;
    }
    ++stats_.commands;
  }

  // A flood of bad messages must not become a flood of status messages: one
  // report per 200 ms, the rest counted (rejected_commands).
  void reportRejection(const std::string& why) {
    const auto t = Clock::now();
    if (t - last_rejection_report_ < std::chrono::milliseconds(200)) return;
    last_rejection_report_ = t;
    publishStatus(driver_.fault() == can::DriverFault::kNone ? plsa_lcm::status_t::OK : plsa_lcm::status_t::FAULT, why);
  }

  // Any message on the clear channel asks; its bytes are not read.
  void onClear(const ::lcm::ReceiveBuffer*, const std::string&) {
    if (driver_.fault() == can::DriverFault::kNone) return;
    const std::string why = can::toString(driver_.fault());
    if (driver_.clearFault(now())) {
      reported_ = can::DriverFault::kNone;
      publishStatus(plsa_lcm::status_t::OK, "fault cleared (was: " + why + ")");
    } else {
      publishStatus(plsa_lcm::status_t::FAULT, "fault not cleared, its cause remains: " + why);
    }
  }

  void publishState() {
    plsa_lcm::actuator_state_t m;
    m.utime = epochMicroseconds();
    m.seq = stats_.states++;
    m.n_chambers = 3;
    m.command_bar.assign(driver_.output().begin(), driver_.output().end());
    m.pressure_bar.assign(driver_.pressures().begin(), driver_.pressures().end());
    const double nan = std::numeric_limits<double>::quiet_NaN();
    m.bend_deg = driver_.hasTipAngle() ? driver_.tipAngle()[0] : nan;
    m.steer_deg = driver_.hasTipAngle() ? driver_.tipAngle()[1] : nan;
    for (auto& row : m.sensor_rotation)
      for (double& v : row) v = nan;  // the bus carries angles, not the rotation
    // Vented only if the vent frame went out: a bus-off controller sends nothing.
    m.vented = driver_.fault() != can::DriverFault::kNone && driver_.lastFrameSent() ? 1 : 0;
    lcm_.publish(o_.state_channel, &m);
  }

  void publishStatus(int8_t state, const std::string& message) {
    const can::DriverCounters& c = driver_.counters();
    const can::TransportStats t = transport_.stats();
    plsa_lcm::status_t s;
    s.utime = epochMicroseconds();
    s.source = "plsa can-bridge";
    s.state = state;
    s.message = message;
    s.names = {"sensor_frames",     "tip_frames",   "bad_length",           "bad_checksum",
               "counter_gaps",      "valve_frames", "send_failures",        "commands",
               "rejected_commands", "rx_overflows", "back_pressure",        "malformed_frames",
               "bus_state",         "faults",       "overpressure_readings"};
    s.values = {static_cast<double>(c.sensor_frames),
                static_cast<double>(c.tip_frames),
                static_cast<double>(c.bad_length),
                static_cast<double>(c.bad_checksum),
                static_cast<double>(c.counter_gaps),
                static_cast<double>(c.valve_frames),
                static_cast<double>(c.send_failures),
                static_cast<double>(stats_.commands),
                static_cast<double>(stats_.rejected_commands),
                static_cast<double>(t.overflows),
                static_cast<double>(t.back_pressure),
                static_cast<double>(t.malformed),
                static_cast<double>(transport_.busState()),
                static_cast<double>(stats_.faults),
                static_cast<double>(c.overpressure_readings)};
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
  plsa_lcm::pressure_command_t command_;
  Clock::time_point last_rejection_report_{};
  bool vented_on_exit_ = false;
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
        << " of " << timeout << " s needs a tick at least every " << timeout / 2 << " s (--rate " << 2.0 / timeout
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
