// `plsa simulate`: run an experiment on the simulated actuator and write a log;
// `plsa sim-config`: write the default simulator configuration to edit.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/io/log_readers.hpp"
#include "plsa/sim/experiment.hpp"

namespace plsa::app {
namespace {

struct SimulateOptions {
  std::string config;
  std::string channel = "PLSA_STATE";
  std::string experiment = "grid2";
  double duration_s = 0.0;
  std::uint64_t seed = 1;
  std::string out;
};

void runSimulate(const SimulateOptions& o) {
  checkOutputPath(o.out, "--out", {o.config}, "plsa simulate");
  const sim::SimConfig config = o.config.empty() ? sim::SimConfig{} : sim::loadSimConfig(o.config);
  sim::ExperimentOptions eo;
  eo.sample_rate_hz = config.sample_rate_hz;
  eo.seed = o.seed;
  if (o.duration_s > 0) {
    if (o.experiment == "joystick") {
      eo.joystick_duration_s = o.duration_s;
    } else if (o.experiment == "static_map") {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "--duration does not apply to static_map: it holds each of its %d x %d points %g s",
                    eo.static_map_points, eo.static_map_points, eo.static_map_hold_s);
      throw std::invalid_argument(msg);
    } else {
      // Spread the duration over the levels of the staircase or grid: the
      // recorded time is a fixed part (rest, first level) plus one hold per level.
      auto recorded = [&](double hold_s) {
        sim::ExperimentOptions probe = eo;
        probe.hold_s = hold_s;
        const sim::Experiment e = sim::makeExperiment(o.experiment, probe);
        return static_cast<double>(e.commands.rows() - e.record_from) / eo.sample_rate_hz;
      };
      const double at_hold = recorded(eo.hold_s);
      const double levels = (recorded(2 * eo.hold_s) - at_hold) / eo.hold_s;
      const double fixed_s = at_hold - levels * eo.hold_s;
      eo.hold_s = (o.duration_s - fixed_s) / levels;
      if (eo.hold_s < 1.0 / eo.sample_rate_hz)
        throw std::invalid_argument("--duration " + std::to_string(o.duration_s) + " s is too short for " +
                                    o.experiment + ": it records " + std::to_string(fixed_s) +
                                    " s before its first step");
    }
  }
  const sim::Experiment ex = sim::makeExperiment(o.experiment, eo);
  // What is recorded, then the pre-roll that is simulated but not written.
  const double recorded_s = static_cast<double>(ex.commands.rows() - ex.record_from) / eo.sample_rate_hz;
  const double preroll_s = static_cast<double>(ex.record_from) / eo.sample_rate_hz;
  char shape[64];
  if (o.experiment == "joystick")
    std::snprintf(shape, sizeof shape, "bandwidth %.2f Hz", eo.joystick_bandwidth_hz);
  else if (o.experiment == "static_map")
    std::snprintf(shape, sizeof shape, "%d x %d points, hold %.0f s each", eo.static_map_points, eo.static_map_points,
                  eo.static_map_hold_s);
  else
    std::snprintf(shape, sizeof shape, "hold %.2f s per level", eo.hold_s);
  std::fprintf(stderr, "plsa simulate: %s, %.1f s recorded at %.0f Hz after a %.1f s pre-roll (%s), seed %llu\n",
               ex.name.c_str(), recorded_s, eo.sample_rate_hz, preroll_s, shape,
               static_cast<unsigned long long>(o.seed));
  sim::Actuator actuator(config, o.seed);
  io::Log log = sim::runExperiment(actuator, ex);
  log.metadata["seed"] = std::to_string(o.seed);
  io::WriteOptions wo;
  wo.lcm_channel = o.channel;
  io::writeLog(o.out, log, wo);  // by the extension: .lcmlog an LCM event log, else CSV
  std::fprintf(stderr, "plsa simulate: wrote %lld samples to %s (effects: %s)\n", static_cast<long long>(log.samples()),
               o.out.c_str(), log.metadata["effects"].c_str());
}

}  // namespace

void addSimulateCommands(CLI::App& app) {
  auto o = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand("simulate", "Run an experiment on the simulated actuator, write a CSV log");
  cmd->add_option("--config", o->config, "Simulator configuration (JSON); default: built-in, all effects on")
      ->check(CLI::ExistingFile);
  cmd->add_option("--experiment", o->experiment,
                  "staircase1, grid2, joystick; not the paper's: grid2_joint (grid2, then both chambers moving "
                  "at once along its diagonals) or static_map (both grid chambers step together from 0.19 bar to "
                  "each of 7 x 7 points over the grid's range and hold 40 s)")
      ->check(CLI::IsMember({"staircase1", "grid2", "grid2_joint", "joystick", "static_map"}));
  cmd->add_option("--duration", o->duration_s,
                  "Recorded duration in seconds (default: the design's own; joystick: its moving part, after 1 s "
                  "held at the start)")
      ->check(kPositive);
  cmd->add_option("--seed", o->seed, "Random seed (noise, joystick); same seed, same file")->check(kSeed);
  cmd->add_option("--out", o->out, "Output log: .csv, or .lcmlog for an LCM event log ('-': CSV on standard output)")
      ->required()
      ->check(kOutputPath);
  cmd->add_option("--channel", o->channel, "LCM event log: the channel the actuator-state messages go on");
  cmd->callback([o] { runSimulate(*o); });

  auto path = std::make_shared<std::string>();
  CLI::App* cfg = app.add_subcommand("sim-config", "Write the default simulator configuration (JSON)");
  cfg->add_option("--out", *path, "Output file")->required()->check(kOutputPath);
  cfg->callback(
      [path] { writeTextFile(*path, sim::simConfigToJson(sim::SimConfig{}) + "\n", "simulator configuration"); });
}

}  // namespace plsa::app
