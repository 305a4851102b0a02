// `plsa sim`: the simulated actuator as an LCM node. SIGINT/SIGTERM stop it
// cleanly: it vents every chamber and publishes a final status first.
#include <csignal>
#include <cstdio>
#include <memory>

#include "commands.hpp"
#include "stop_signal.hpp"
#include "plsa/can/udp_transport.hpp"
#include "plsa/lcm/sim_node.hpp"

namespace plsa::app {
namespace {

struct SimNodeArgs {
  lcm::SimNodeOptions node;
  std::string config;
  std::string can;      // transport spec: the device sits behind CAN instead of LCM commands
  std::string profile;  // signal map (default profile when empty)
};

void runSimCan(SimNodeArgs& a) {
  const can::SignalMap map = a.profile.empty() ? can::defaultSignalMap() : can::loadSignalMap(a.profile);
  for (const auto& w : can::driverProfileWarnings(map)) std::fprintf(stderr, "plsa sim: warning: %s\n", w.c_str());
  auto transport = can::openTransport(a.can, {map.message("valve_command").id});
  const std::atomic<bool>& stop = stopOnSignals();
  std::fprintf(stderr, "plsa sim: behind CAN (%s, profile %s) at %.0f Hz; true state on LCM channel %s\n",
               a.can.c_str(), map.profile.c_str(), a.node.config.sample_rate_hz, a.node.state_channel.c_str());
  const lcm::SimNodeStats s = lcm::runSimCanNode(a.node, *transport, map, stop);
  std::fprintf(stderr,
               "plsa sim: stopped; %lld samples, %lld valve frames, %lld bad valve frames, "
               "%lld sensor frames not sent, %lld readings saturated at the profile's full scale, "
               "%lld vents after a command silence\n",
               static_cast<long long>(s.states_published), static_cast<long long>(s.commands_accepted),
               static_cast<long long>(s.commands_rejected), static_cast<long long>(s.sensor_frames_lost),
               static_cast<long long>(s.saturated_readings), static_cast<long long>(s.vent_events));
}

void runSimNodeCommand(SimNodeArgs& a) {
  if (!a.config.empty()) a.node.config = sim::loadSimConfig(a.config);
  if (!a.can.empty()) return runSimCan(a);
  const std::atomic<bool>& stop = stopOnSignals();
  std::fprintf(stderr, "plsa sim: %s at %.0f Hz, command timeout %.3f s, LCM %s\n",
               a.node.lockstep ? "lock-step" : "real time", a.node.config.sample_rate_hz, a.node.command_timeout_s,
               a.node.url.empty() ? "(LCM_DEFAULT_URL or LCM default)" : a.node.url.c_str());
  const lcm::SimNodeStats s = lcm::runSimNode(a.node, stop);
  std::fprintf(
      stderr,
      "plsa sim: stopped, chambers vented; %lld states, %lld commands accepted, %lld rejected, %lld vent events\n",
      static_cast<long long>(s.states_published), static_cast<long long>(s.commands_accepted),
      static_cast<long long>(s.commands_rejected), static_cast<long long>(s.vent_events));
}

}  // namespace

void addSimNodeCommand(CLI::App& app) {
  auto a = std::make_shared<SimNodeArgs>();
  CLI::App* cmd = app.add_subcommand("sim", "Run the simulated actuator as an LCM node");
  cmd->add_option("--config", a->config, "Simulator configuration (JSON)")->check(CLI::ExistingFile);
  cmd->add_option("--url", a->node.url, "LCM URL (default: LCM_DEFAULT_URL)");
  cmd->add_option("--seed", a->node.seed, "Noise seed")->check(kSeed);
  cmd->add_flag("--lockstep", a->node.lockstep, "Advance one sample per command instead of in real time");
  cmd->add_option("--command-timeout", a->node.command_timeout_s,
                  "Vent when no command (behind CAN: no valid valve frame) for this long (s)")
      ->check(kPositive);
  cmd->add_option("--duration", a->node.duration_s, "Stop after this many simulated seconds (0: run until signalled)")
      ->check(kNonNegative);
  cmd->add_option("--command-channel", a->node.command_channel, "Channel of pressure commands");
  cmd->add_option("--state-channel", a->node.state_channel, "Channel of actuator state");
  cmd->add_option("--status-channel", a->node.status_channel, "Channel of status messages");
  cmd->add_option("--can", a->can,
                  "Sit behind CAN instead of LCM commands: can0, socketcan:<iface> or udp:<listen-port>:<peer-port>");
  cmd->add_option("--profile", a->profile, "CAN signal map: JSON or a DBC file (.dbc) (default: the built-in profile)")
      ->check(CLI::ExistingFile);
  cmd->callback([a] { runSimNodeCommand(*a); });
}

}  // namespace plsa::app
