// `plsa convert`: a log from any format this build reads (CSV, LCM event
// logs, candump bus logs) into any it writes, chosen by the output's name:
// how a bus recording becomes a CSV to look at, or a run one to replay.
// `plsa can-profile`: a CAN signal map (plsa's default, a JSON profile or a
// DBC file) written as DBC or JSON.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "log_paths.hpp"
#include "plsa/can/dbc.hpp"
#include "plsa/can/signal_map.hpp"
#include "plsa/core/text_file.hpp"
#include "plsa/io/log_readers.hpp"

namespace plsa::app {

namespace {

struct ConvertArgs {
  std::string in, out;
  std::string channel = "PLSA_STATE";
  std::string can_profile;
};

void runConvert(const ConvertArgs& a) {
  checkOutputPath(a.out, "--out", {a.in, a.can_profile}, "plsa convert");
  logPaths({a.in}, "convert", false);  // a file or a pipe; a device is no log
  io::ReadOptions ro;
  ro.lcm_channel = a.channel;
  ro.can_profile = a.can_profile;
  const io::Log log = readLogWithWarnings(a.in, ro, "convert");
  io::WriteOptions wo;
  wo.lcm_channel = a.channel;
  wo.can_profile = a.can_profile;
  io::writeLog(a.out, log, wo);
  // What the file holds, read back as the tools will read it: a format that
  // carries fixed columns (LCM's standard state, a signal map's signals)
  // leaves the others out, and that is said (a probe's cmd_4 and p_4 went
  // missing under a message listing them as written).
  const io::Log written = io::readLog(a.out, ro);
  std::vector<std::string> left_out;
  for (const std::string& c : log.columns)
    if (!written.hasColumn(c)) left_out.push_back(c);
  if (!left_out.empty())
    std::fprintf(stderr, "plsa convert: warning: %s holds no column for %s (its format carries only %s)\n",
                 a.out.c_str(), io::columnList(left_out).c_str(), io::columnList(written.columns).c_str());
  std::printf("plsa convert: %s -> %s: %lld rows, columns %s\n", a.in.c_str(), a.out.c_str(),
              static_cast<long long>(written.samples()), io::columnList(written.columns).c_str());
}

struct CanProfileArgs {
  std::string in, out;
};

void runCanProfile(const CanProfileArgs& a) {
  checkOutputPath(a.out, "--out", {a.in}, "plsa can-profile");
  const can::SignalMap map = a.in.empty() ? can::defaultSignalMap() : can::loadSignalMap(a.in);
  for (const std::string& w : can::driverProfileWarnings(map))
    std::fprintf(stderr, "plsa can-profile: warning: %s\n", w.c_str());
  const bool dbc = a.out.size() > 4 && a.out.compare(a.out.size() - 4, 4, ".dbc") == 0;
  writeTextFile(a.out, dbc ? can::signalMapToDbc(map) : can::signalMapToJson(map), dbc ? "DBC file" : "signal map");
  std::printf("plsa can-profile: '%s' (%zu messages) -> %s\n", map.profile.c_str(), map.messages.size(), a.out.c_str());
}

}  // namespace

void addCanProfileCommand(CLI::App& app) {
  auto a = std::make_shared<CanProfileArgs>();
  auto* c = app.add_subcommand("can-profile", "Write a CAN signal map as DBC (.dbc) or plsa's JSON (any other name)");
  c->add_option("--in", a->in, "Signal map to read: a DBC file (.dbc) or JSON (default: plsa's profile)")
      ->check(CLI::ExistingFile);
  c->add_option("--out", a->out, "File to write: .dbc for DBC, else JSON")->required()->check(kOutputPath);
  c->callback([a] { runCanProfile(*a); });
}

void addConvertCommand(CLI::App& app) {
  auto a = std::make_shared<ConvertArgs>();
  auto* c = app.add_subcommand("convert", "Convert a log between formats (CSV, LCM event log, candump bus log)");
  c->add_option("--in", a->in, "Log to read (its format known by content or name)")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("--out", a->out, "Log to write: .csv, .candump, or .lcmlog in a build with LCM")
      ->required()
      ->check(kOutputPath);
  addLogFormatOptions(c, a->channel, a->can_profile);
  c->callback([a] { runConvert(*a); });
}

}  // namespace plsa::app
