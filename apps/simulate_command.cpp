// `plsa simulate`: run an experiment on the simulated actuator and write a log;
// `plsa sim-config`: write the default simulator configuration to edit.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/lcm/lcm_log.hpp"
#include "plsa/sim/experiment.hpp"

namespace plsa::app {
namespace {

struct SimulateOptions {
  std::string config;
  std::string experiment = "grid2";
  double duration_s = 0.0;
  std::uint64_t seed = 1;
  std::string out;
};

void runSimulate(const SimulateOptions& o) {
  const sim::SimConfig config = o.config.empty() ? sim::SimConfig{} : sim::loadSimConfig(o.config);
  sim::ExperimentOptions eo;
  eo.sample_rate_hz = config.sample_rate_hz;
  eo.seed = o.seed;
  if (o.duration_s > 0) {
    if (o.experiment == "joystick") {
      eo.joystick_duration_s = o.duration_s;
    } else {
      // Spread the duration over the levels of the staircase or grid.
      const sim::Experiment probe = sim::makeExperiment(o.experiment, eo);
      const double levels = (probe.commands.rows() / eo.sample_rate_hz - eo.initial_rest_s) / eo.hold_s;
      eo.hold_s = (o.duration_s - eo.initial_rest_s) / levels;
      if (eo.hold_s <= 0) throw std::invalid_argument("--duration is too short for this experiment");
    }
  }
  const sim::Experiment ex = sim::makeExperiment(o.experiment, eo);
  std::fprintf(stderr, "plsa simulate: %s, %.1f s at %.0f Hz (hold %.2f s per level), seed %llu\n",
               ex.name.c_str(), ex.commands.rows() / eo.sample_rate_hz, eo.sample_rate_hz, eo.hold_s,
               static_cast<unsigned long long>(o.seed));
  sim::Actuator actuator(config, o.seed);
  io::Log log = sim::runExperiment(actuator, ex);
  log.metadata["seed"] = std::to_string(o.seed);
  const bool lcm_out = o.out.size() > 7 && o.out.compare(o.out.size() - 7, 7, ".lcmlog") == 0;
  if (lcm_out)
    lcm::writeLcmLog(o.out, log);
  else
    io::writeCsvLog(o.out, log);
  std::fprintf(stderr, "plsa simulate: wrote %lld samples to %s (effects: %s)\n",
               static_cast<long long>(log.samples()), o.out.c_str(), log.metadata["effects"].c_str());
}

}  // namespace

void addSimulateCommands(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Run an experiment on the simulated actuator, write a CSV log");
  cmd->add_option("--config", o->config, "Simulator configuration (JSON); default: built-in, all effects on")
      ->check(CLI::ExistingFile);
  cmd->add_option("--experiment", o->experiment, "staircase1, grid2 or joystick")
      ->check(CLI::IsMember({"staircase1", "grid2", "joystick"}));
  cmd->add_option("--duration", o->duration_s, "Total duration in seconds (default: the design's own)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o->seed, "Random seed (noise, joystick); same seed, same file");
  cmd->add_option("--out", o->out, "Output log: .csv, or .lcmlog for an LCM event log")->required();
  cmd->callback([o] { runSimulate(*o); });

  auto path = std::make_shared<std::string>();
  CLI::App* cfg = app.add_subcommand("sim-config", "Write the default simulator configuration (JSON)");
  cfg->add_option("--out", *path, "Output file")->required();
  cfg->callback([path] {
    writeTextFile(*path, sim::simConfigToJson(sim::SimConfig{}) + "\n", "simulator configuration");
  });
}

}  // namespace plsa::app
