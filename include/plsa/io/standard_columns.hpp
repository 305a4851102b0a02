// The column names of a three-chamber actuator's log as plsa's recorders
// write them (the simulator, the LCM and CAN nodes, the self-check) and its
// tools take them by default: time, the commanded and measured chamber
// pressures, and the tip's bending and steering angles. Logs with other
// names work everywhere (name the columns); these are the defaults, defined
// once.
#pragma once

#include <string>
#include <vector>

namespace plsa::io::standard_columns {

inline constexpr char kTime[] = "time_s";         ///< seconds
inline constexpr char kBend[] = "bend_deg";       ///< tip bending angle, deg
inline constexpr char kSteer[] = "steer_deg";     ///< tip steering (bending direction) angle, deg
inline constexpr char kCommandPrefix[] = "cmd_";  ///< cmd_1.. commanded pressure, bar
inline constexpr char kPressurePrefix[] = "p_";   ///< p_1.. measured pressure, bar
inline constexpr int kChambers = 3;

/// "cmd_<chamber>" and "p_<chamber>", chambers counted from 1.
inline std::string command(int chamber) { return kCommandPrefix + std::to_string(chamber); }
inline std::string pressure(int chamber) { return kPressurePrefix + std::to_string(chamber); }

inline std::vector<std::string> commands() {
  std::vector<std::string> names;
  for (int c = 1; c <= kChambers; ++c) names.push_back(command(c));
  return names;
}
inline std::vector<std::string> pressures() {
  std::vector<std::string> names;
  for (int c = 1; c <= kChambers; ++c) names.push_back(pressure(c));
  return names;
}
inline std::vector<std::string> tipAngles() { return {kBend, kSteer}; }

/// A recorded run's columns in the order the recorders write them: time,
/// commands, pressures, bending, steering.
inline std::vector<std::string> recorded() {
  std::vector<std::string> names{kTime};
  for (const auto& group : {commands(), pressures(), tipAngles()})
    names.insert(names.end(), group.begin(), group.end());
  return names;
}

}  // namespace plsa::io::standard_columns
