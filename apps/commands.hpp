// Subcommands of the `plsa` tool; each registers itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

namespace plsa::app {

void addDemoCommand(CLI::App& app);
void addSimulateCommands(CLI::App& app);
void addSimNodeCommand(CLI::App& app);
void addIdentifyCommands(CLI::App& app);
void addCrossvalCommand(CLI::App& app);
void addPredictCommand(CLI::App& app);
void addCanBridgeCommand(CLI::App& app);
void addDiagnoseCommands(CLI::App& app);

}  // namespace plsa::app
