// Subcommands of the `plsa` tool; each registers itself on the CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include "plsa/identify/pipeline.hpp"

namespace plsa::app {

/// An option taking one of an enum's values by its spelling (OptionSpelling):
/// the help lists the spellings and shows the default's.
template <class E>
CLI::Option* addChoice(CLI::App* app, const std::string& flag, E& target, const std::string& help) {
  std::vector<std::string> names;
  for (const auto& value : identify::OptionSpelling<E>::values) names.emplace_back(value.second);
  return app
      ->add_option_function<std::string>(
          flag, [&target](const std::string& name) { target = identify::parseOption<E>(name); }, help)
      ->check(CLI::IsMember(names))
      ->default_str(identify::optionName(target));
}

/// Number checks with a short message (CLI11's own print the largest double in full).
inline CLI::Validator finiteNumberAtLeast(double lo, bool strict) {
  const std::string what = strict ? "a finite number above " : "a finite number at least ";
  return CLI::Validator(
      [lo, strict, what](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        const bool ok = !text.empty() && end && *end == '\0' && std::isfinite(v) && (strict ? v > lo : v >= lo);
        return ok ? std::string() : "'" + text + "' is not " + what + CLI::detail::to_string(lo);
      },
      strict ? "POSITIVE" : "NONNEGATIVE");
}
inline const CLI::Validator kPositive = finiteNumberAtLeast(0.0, true);
/// Any finite number ("nan" passes CLI::Range: its comparisons are false),
/// or an infinity where `infinities` (a threshold meaning always or never).
inline CLI::Validator finiteNumber(bool infinities = false) {
  return CLI::Validator(
      [infinities](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        const bool ok = !text.empty() && end && *end == '\0' && !std::isnan(v) && (infinities || std::isfinite(v));
        return ok ? std::string() : "'" + text + "' is not a " + (infinities ? "number" : "finite number");
      },
      "NUMBER");
}
inline const CLI::Validator kNonNegative = finiteNumberAtLeast(0.0, false);

/// A path to write: an empty one is refused by name (`--csv ''` was taken as
/// "not given", and the run ended without the file asked for).
inline const CLI::Validator kOutputPath = CLI::Validator(
    [](std::string& text) -> std::string { return text.empty() ? "an empty path names no file" : std::string(); },
    "PATH");

/// A random seed as digits only: CLI11 reads "-3" as 2^64 - 3 and clamps an
/// overlong one to 2^64 - 1, each a different run from the one asked for.
inline const CLI::Validator kSeed = CLI::Validator(
    [](std::string& text) -> std::string {
      const bool digits =
          !text.empty() && text.size() <= 20 && text.find_first_not_of("0123456789") == std::string::npos;
      // 20 digits may still pass 2^64 - 1; the comparison is as text of equal length.
      const bool fits = digits && (text.size() < 20 || text <= "18446744073709551615");
      return fits ? std::string() : "'" + text + "' is not a seed (a whole number from 0 to 18446744073709551615)";
    },
    "SEED");

/// The whole of `text` as a finite number >= 0, else false.
inline bool parseNonNegative(const std::string& text, double& value) {
  std::size_t used = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used > 0 && used == text.size() && std::isfinite(value) && value >= 0;
}

/// How a command reads logs of other formats: the LCM channel of the
/// actuator-state messages and the signal map of a candump log's bus.
inline void addLogFormatOptions(CLI::App* app, std::string& channel, std::string& can_profile) {
  app->add_option("--channel", channel, "LCM logs: the channel of the actuator-state messages");
  app->add_option("--can-profile", can_profile,
                  "candump logs: the signal map of their bus, JSON or DBC (default: plsa's)")
      ->check(CLI::ExistingFile);
}

void addDemoCommand(CLI::App& app);
void addSimulateCommands(CLI::App& app);
void addSimNodeCommand(CLI::App& app);
void addIdentifyCommands(CLI::App& app);
void addValidateCommand(CLI::App& app);
void addCrossvalCommand(CLI::App& app);
/// identify's --play-bank and --play-bank-min-gain, into `options` (crossval's too).
void addPlayBankOptions(CLI::App* app, identify::IdentifyOptions& options);
void addConvertCommand(CLI::App& app);
void addCanProfileCommand(CLI::App& app);
void addPredictCommand(CLI::App& app);
void addCanBridgeCommand(CLI::App& app);
void addDiagnoseCommands(CLI::App& app);
void addGeneraliseCommand(CLI::App& app);

}  // namespace plsa::app
