// `plsa`: the command-line front end to identification, prediction and diagnosis.
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "plsa/can/candump_log.hpp"
#if PLSA_WITH_LCM
#include "plsa/lcm/lcm_log.hpp"
#endif

// Exit codes: 0 done; 1 the tool failed (bad input, a failed check, a
// target not met), with the reason on standard error; 2 the command line
// itself is wrong (unknown option, a value out of range), with CLI usage.
constexpr int kExitFailed = 1, kExitUsage = 2;

int main(int argc, char** argv) {
  // Progress reaches a pipe or a log line by line, not in one burst at exit.
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  plsa::can::registerLogFormats();  // candump bus logs, read wherever a tool takes a log
#if PLSA_WITH_LCM
  plsa::lcm::registerLogFormats();  // LCM event logs, read and written wherever a tool takes a log
#endif
  CLI::App app{"plsa: identify and predict pneumatic soft actuators (DIO-PWL-OBF)"};
  app.option_defaults()->always_capture_default();  // --help shows every default
  app.footer("Exit codes: 0 done; 1 failed (reason on standard error); 2 usage error.");
  app.set_version_flag("--version", std::string("plsa ") + PLSA_VERSION);
  app.require_subcommand(1);
  plsa::app::addDemoCommand(app);
  plsa::app::addSimulateCommands(app);
#if PLSA_WITH_LCM
  plsa::app::addSimNodeCommand(app);
#endif
  plsa::app::addIdentifyCommands(app);
  plsa::app::addCrossvalCommand(app);
  plsa::app::addConvertCommand(app);
  plsa::app::addCanProfileCommand(app);
  plsa::app::addGeneraliseCommand(app);
#if PLSA_WITH_LCM
  plsa::app::addPredictCommand(app);
  plsa::app::addCanBridgeCommand(app);
#else
  // The LCM nodes are not in this build: absent from --help, named if asked for.
  for (const std::string name : {"sim", "predict", "can-bridge"})
    app.add_subcommand(name, "Needs a build with LCM (this one has PLSA_WITH_LCM=OFF)")
        ->group("")
        ->prefix_command()
        ->callback([name] {
          throw std::invalid_argument("plsa " + name + " needs a build with LCM; this one has PLSA_WITH_LCM=OFF");
        });
#endif
  plsa::app::addDiagnoseCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitUsage;  // --help and --version are not errors
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plsa: error: %s\n", e.what());
    return kExitFailed;
  } catch (...) {
    std::fprintf(stderr, "plsa: error: an unknown exception stopped the tool\n");
    return kExitFailed;
  }
  return 0;
}
