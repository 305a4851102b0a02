#include "plsa/lcm/sim_node.hpp"

#include <poll.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include <lcm/lcm-cpp.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

#include "plsa/can/simulated_valve_device.hpp"
#include "plsa/lcm/message_codec.hpp"
#include "plsa/lcm/state_codec.hpp"
#include "plsa/sim/actuator.hpp"

namespace plsa::lcm {
namespace {

using Clock = std::chrono::steady_clock;

class SimNode {
 public:
  SimNode(const SimNodeOptions& o, const std::atomic<bool>& stop)
      : o_(o), stop_(stop), lcm_(o.url), actuator_(o.config, o.seed), origin_us_(epochMicroseconds()) {
    if (!lcm_.good())
      throw std::runtime_error("plsa sim: cannot open LCM at '" + (o.url.empty() ? "default" : o.url) + "'");
    lcm_.subscribe(o.command_channel, &SimNode::onCommand, this);
    period_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / o.config.sample_rate_hz));
    timeout_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.command_timeout_s));
  }

  SimNodeStats run() {
    try {
      publishStatus(plsa_lcm::status_t::VENTED, "started; chambers vented until the first command");
      if (o_.lockstep)
        runLockstep();
      else
        runRealtime();
    } catch (const std::exception& e) {
      ventOnExit(std::string("stopped by an error: ") + e.what() + "; chambers vented");
      throw;
    }
    ventOnExit("stopped; chambers vented");
    return stats_;
  }

 private:
  // Leave the device safe, and say so.
  void ventOnExit(const std::string& why) {
    command_ = {0, 0, 0};
    vented_ = true;
    publishState(actuator_.vent(), true);
    publishStatus(plsa_lcm::status_t::STOPPED, why);
  }

  // Raw bytes: decoded by the checked decoder, never by lcm-gen's alone.
  void onCommand(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    std::string why = decodeMessage(rbuf->data, rbuf->data_size, message_);
    if (why.empty() && message_.n_chambers != 3)
      why = "n_chambers = " + std::to_string(message_.n_chambers) + ", this actuator has 3";
    for (std::size_t i = 0; why.empty() && i < 3; ++i)
      if (!std::isfinite(message_.pressure_bar[i])) why = "pressure_bar[" + std::to_string(i) + "] is NaN or Inf";
    if (!why.empty()) {
      ++stats_.commands_rejected;
      const auto t = Clock::now();
      if (t - last_rejection_report_ >= std::chrono::milliseconds(200)) {  // a flood is counted, not echoed
        last_rejection_report_ = t;
        publishStatus(vented_ ? plsa_lcm::status_t::VENTED : plsa_lcm::status_t::OK,
                      "rejected a command on " + channel + ": " + why);
      }
      return;
    }
    ++stats_.commands_accepted;
    const plsa_lcm::pressure_command_t* m = &message_;
    command_ = {m->pressure_bar[0], m->pressure_bar[1], m->pressure_bar[2]};
    last_command_ = Clock::now();
    have_command_ = true;
    fresh_command_ = true;
    if (vented_) {
      vented_ = false;
      publishStatus(plsa_lcm::status_t::OK, "commands resumed");
    }
  }

  // Waits for LCM traffic until `deadline`; returns early after a command if asked.
  void pump(Clock::time_point deadline, bool return_on_command) {
    const int fd = lcm_.getFileno();
    while (!stop_.load()) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      pollfd pfd{fd, POLLIN, 0};
      const int r = ::poll(&pfd, 1, static_cast<int>(std::max<long long>(0, left)));
      if (r > 0) {
        lcm_.handle();
        if (return_on_command && fresh_command_) return;
        continue;
      }
      if (left <= 0) return;
    }
  }

  bool timedOut() const { return !have_command_ || Clock::now() - last_command_ > timeout_; }

  void enterVentIfStale() {
    if (timedOut() && !vented_ && have_command_) {
      vented_ = true;
      ++stats_.vent_events;
      char msg[128];
      std::snprintf(msg, sizeof msg, "no command for %.3f s: venting every chamber", o_.command_timeout_s);
      publishStatus(plsa_lcm::status_t::VENTED, msg);
    }
  }

  bool durationReached() const { return o_.duration_s > 0 && actuator_.time() >= o_.duration_s - 1e-9; }

  void runRealtime() {
    auto next = Clock::now();
    vented_ = true;
    while (!stop_.load() && !durationReached()) {
      next += period_;
      pump(next, false);
      enterVentIfStale();
      const std::array<double, 3> cmd = vented_ ? std::array<double, 3>{0, 0, 0} : command_;
      publishState(actuator_.step(cmd), vented_);
      if (Clock::now() >= last_status_ + std::chrono::seconds(1)) publishPeriodicStatus();
    }
  }

  void runLockstep() {
    // Time advances one sample per command; once commands stop after the
    // first, the node vents and steps on its own at the real-time rate.
    vented_ = true;
    while (!stop_.load() && !durationReached()) {
      fresh_command_ = false;
      const auto wait = vented_ || !have_command_ ? period_ : last_command_ + timeout_ - Clock::now();
      pump(Clock::now() + std::max(wait, Clock::duration::zero()), true);
      if (fresh_command_) {
        publishState(actuator_.step(command_), false);
        continue;
      }
      enterVentIfStale();
      if (vented_ && have_command_) publishState(actuator_.vent(), true);
    }
  }

  void publishState(const sim::ActuatorSample& s, bool vented) {
    const plsa_lcm::actuator_state_t m = toMessage(s, stats_.states_published, vented, origin_us_);
    lcm_.publish(o_.state_channel, &m);
    ++stats_.states_published;
  }

  void publishPeriodicStatus() {
    publishStatus(vented_ ? plsa_lcm::status_t::VENTED : plsa_lcm::status_t::OK,
                  vented_ ? "vented: waiting for commands" : "running");
  }

  void publishStatus(int8_t state, const std::string& message) {
    plsa_lcm::status_t s;
    s.utime = epochMicroseconds();
    s.source = "plsa sim";
    s.state = state;
    s.message = message;
    s.names = {"states_published", "commands_accepted", "commands_rejected", "vent_events", "sim_time_s"};
    s.values = {static_cast<double>(stats_.states_published), static_cast<double>(stats_.commands_accepted),
                static_cast<double>(stats_.commands_rejected), static_cast<double>(stats_.vent_events),
                actuator_.time()};
    s.n_values = static_cast<int32_t>(s.names.size());
    lcm_.publish(o_.status_channel, &s);
    last_status_ = Clock::now();
  }

  SimNodeOptions o_;
  const std::atomic<bool>& stop_;
  ::lcm::LCM lcm_;
  sim::Actuator actuator_;
  std::int64_t origin_us_;  ///< epoch time at simulated time 0: states' utime = origin_us_ + simulated time
  Clock::duration period_{};
  Clock::duration timeout_{};
  std::array<double, 3> command_{0, 0, 0};
  Clock::time_point last_command_{};
  Clock::time_point last_status_{};
  bool have_command_ = false;
  bool fresh_command_ = false;
  bool vented_ = true;
  SimNodeStats stats_;
  plsa_lcm::pressure_command_t message_;
  Clock::time_point last_rejection_report_{};
};

}  // namespace

SimNodeStats runSimNode(const SimNodeOptions& options, const std::atomic<bool>& stop) {
  SimNode node(options, stop);
  return node.run();
}

SimNodeStats runSimCanNode(const SimNodeOptions& o, can::CanTransport& transport, const can::SignalMap& map,
                           const std::atomic<bool>& stop) {
  ::lcm::LCM lcm(o.url);
  if (!lcm.good())
    throw std::runtime_error("plsa sim: cannot open LCM at '" + (o.url.empty() ? "default" : o.url) + "'");
  can::SimulatedValveDevice device(transport, map, o.config, o.seed);
  device.setCommandTimeout(o.command_timeout_s);
  SimNodeStats stats;
  const std::int64_t origin_us = epochMicroseconds();
  const can::SimulatedDeviceStats d =
      can::runSimulatedDevice(device, stop, o.duration_s, [&](const sim::ActuatorSample& s) {
        const bool vented = device.setpoint() == std::array<double, 3>{0, 0, 0};
        const plsa_lcm::actuator_state_t m = toMessage(s, stats.states_published++, vented, origin_us);
        lcm.publish(o.state_channel, &m);
      });
  stats.commands_accepted = d.valve_frames;
  stats.commands_rejected = d.bad_valve_frames;
  stats.sensor_frames_lost = d.send_failures;
  stats.saturated_readings = d.saturated_readings;
  stats.vent_events = d.silence_vents;
  return stats;
}

}  // namespace plsa::lcm
