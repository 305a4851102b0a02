// `plsa`: the command-line front end to identification, prediction and diagnosis.
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>

#include <CLI/CLI.hpp>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "commands.hpp"
#include "plsa/can/candump_log.hpp"
#if PLSA_WITH_LCM
#include "plsa/lcm/lcm_log.hpp"
#endif

// Exit codes: 0 done; 1 the tool failed (bad input, a failed check, a
// target not met), with the reason on standard error; 2 the command line
// itself is wrong (unknown option, a value out of range), with CLI usage.
constexpr int kExitFailed = 1, kExitUsage = 2;

// glibc returns freed memory to the kernel past a trim threshold and maps
// larger blocks afresh, both adjusted as blocks are freed: identification's
// and calibration's buffers, allocated and freed over and over by several
// threads, were faulted in again each time (a diagnosis of three 60 s runs
// spent 1.8 s of its 20 s of CPU in the kernel, its reference identification
// 1.6 of 5). Fixed thresholds keep them for reuse: blocks up to 32 MB (glibc's
// largest threshold) come from the heap and up to 256 MB of free heap is kept.
void keepFreedMemory() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 256 * 1024 * 1024);
#endif
}

int main(int argc, char** argv) {
  keepFreedMemory();
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
