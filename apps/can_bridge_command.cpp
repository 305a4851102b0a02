// `plsa can-bridge`: LCM pressure commands to the valves over CAN, sensor
// frames back as LCM actuator state. SIGINT/SIGTERM vent every chamber.
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "plsa/can/udp_transport.hpp"
#include "plsa/lcm/can_bridge.hpp"
#include "stop_signal.hpp"

namespace plsa::app {

void addCanBridgeCommand(CLI::App& app) {
  auto o = std::make_shared<lcm::CanBridgeOptions>();
  auto iface = std::make_shared<std::string>();
  auto profile = std::make_shared<std::string>();
  CLI::App* c =
      app.add_subcommand("can-bridge", "Bridge LCM pressure commands and actuator state to CAN valves and sensors");
  c->add_option("--iface", *iface, "can0, socketcan:<iface>, or udp:<listen-port>:<peer-port>[?drop=..&delay_us=..]")
      ->required();
  c->add_option("--profile", *profile,
                "Signal map: JSON or a DBC file (.dbc) (default: the built-in profile, docs/can.md)")
      ->check(CLI::ExistingFile);
  c->add_option("--url", o->url, "LCM URL (default: LCM_DEFAULT_URL)");
  c->add_option("--rate", o->rate_hz, "Driver ticks and state messages per second (at most 1000)");
  c->add_option("--max-pressure", o->limits.max_pressure_bar, "Set-point clamp (bar)")->check(kPositive);
  c->add_option("--max-rate", o->limits.max_rate_bar_per_s, "Set-point rate limit (bar/s)")->check(kPositive);
  c->add_option("--sensor-timeout", o->limits.sensor_timeout_s, "Vent when no valid reading for this long (s)")
      ->check(kPositive);
  c->add_option("--command-timeout", o->limits.command_timeout_s, "Vent when commands stop for this long (s)")
      ->check(kPositive);
  c->add_option("--overpressure-margin", o->limits.overpressure_margin_bar,
                "Vent and latch a fault when a chamber reads this far above --max-pressure (bar)")
      ->check(kPositive);
  c->add_option("--duration", o->duration_s, "Stop after this many seconds (0: until signalled)")->check(kNonNegative);
  c->add_option("--command-channel", o->command_channel, "Channel of pressure commands");
  c->add_option("--state-channel", o->state_channel, "Channel for actuator state");
  c->add_option("--status-channel", o->status_channel, "Channel for status");
  c->add_option("--clear-channel", o->clear_channel, "Any message here clears a latched fault if its cause is gone");
  c->callback([o, iface, profile] {
    const can::SignalMap map = profile->empty() ? can::defaultSignalMap() : can::loadSignalMap(*profile);
    lcm::checkCanBridgeOptions(*o, map);  // before the bus is opened
    for (const auto& w : can::driverProfileWarnings(map))
      std::fprintf(stderr, "plsa can-bridge: warning: %s\n", w.c_str());
    std::vector<std::uint32_t> ids{map.message("pressure_sensor").id};
    if (const can::MessageLayout* tip = map.find("tip_angle")) ids.push_back(tip->id);
    auto transport = can::openTransport(*iface, ids);
    const std::atomic<bool>& stop = stopOnSignals();
    std::fprintf(stderr, "plsa can-bridge: %s (profile %s), %s -> valves, sensors -> %s; clamp %.3f bar\n",
                 iface->c_str(), map.profile.c_str(), o->command_channel.c_str(), o->state_channel.c_str(),
                 o->limits.max_pressure_bar);
    const lcm::CanBridgeStats s = lcm::runCanBridge(*o, *transport, map, stop);
    std::fprintf(
        stderr,
        "plsa can-bridge: stopped, vent frame sent; %lld states, %lld commands, %lld rejected, %lld faults%s%s\n",
        static_cast<long long>(s.states), static_cast<long long>(s.commands),
        static_cast<long long>(s.rejected_commands), static_cast<long long>(s.faults), s.faults ? "; last: " : "",
        s.faults ? can::toString(s.last_fault) : "");
  });
}

}  // namespace plsa::app
