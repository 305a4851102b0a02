// `plsa`: the command-line front end to identification, prediction and diagnosis.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"plsa: identify and predict pneumatic soft actuators (DIO-PWL-OBF)"};
  app.set_version_flag("--version", std::string("plsa ") + PLSA_VERSION);
  app.require_subcommand(1);
  plsa::app::addDemoCommand(app);
  plsa::app::addSimulateCommands(app);
#if PLSA_WITH_LCM
  plsa::app::addSimNodeCommand(app);
#endif
  plsa::app::addIdentifyCommands(app);
  plsa::app::addCrossvalCommand(app);
#if PLSA_WITH_LCM
  plsa::app::addPredictCommand(app);
  plsa::app::addCanBridgeCommand(app);
#endif
  plsa::app::addDiagnoseCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plsa: error: %s\n", e.what());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "plsa: error: an unknown exception stopped the tool\n");
    return 1;
  }
  return 0;
}
