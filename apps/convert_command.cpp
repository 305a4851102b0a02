// `plsa convert`: a log from any format this build reads (CSV, LCM event
// logs, candump bus logs) into any it writes, chosen by the output's name:
// how a bus recording becomes a CSV to look at, or a run one to replay.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/io/log_readers.hpp"

namespace plsa::app {

namespace {

struct ConvertArgs {
  std::string in, out;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
};

void runConvert(const ConvertArgs& a) {
  refuseOverwritingInputs(a.out, "--out", {a.in}, "plsa convert");
  io::ReadOptions ro;
  ro.lcm_channel = a.channel;
  ro.can_profile = a.can_profile;
  const io::Log log = readLogWithWarnings(a.in, ro, "convert");
  io::WriteOptions wo;
  wo.lcm_channel = a.channel;
  wo.can_profile = a.can_profile;
  io::writeLog(a.out, log, wo);
  std::printf("plsa convert: %s -> %s: %lld rows, columns %s\n", a.in.c_str(), a.out.c_str(),
              static_cast<long long>(log.samples()),
              [&] {
                std::string c;
                for (const auto& name : log.columns) c += (c.empty() ? "" : ", ") + name;
                return c;
              }()
                  .c_str());
}

}  // namespace

void addConvertCommand(CLI::App& app) {
  auto a = std::make_shared<ConvertArgs>();
  auto* c = app.add_subcommand("convert", "Convert a log between formats (CSV, LCM event log, candump bus log)");
  c->add_option("--in", a->in, "Log to read (its format known by content or name)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--out", a->out, "Log to write: .csv, .candump, or .lcmlog in a build with LCM")->required();
  c->add_option("--channel", a->channel, "LCM logs: the channel of the actuator-state messages");
  c->add_option("--can-profile", a->can_profile, "candump logs: the signal map JSON of their bus (default: plsa's)")
      ->check(CLI::ExistingFile);
  c->callback([a] { runConvert(*a); });
}

}  // namespace plsa::app
