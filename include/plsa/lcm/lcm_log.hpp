// LCM event logs (the lcm-logger format) as plsa logs: actuator-state
// messages become rows with the standard column names, so every tool that
// reads CSV also reads a recording.
#pragma once

#include <string>

#include "plsa/io/csv_log.hpp"

namespace plsa::lcm {

/// Reads the actuator-state messages on `channel`. Other channels are skipped
/// (and counted in the log's metadata). Throws naming the file and event on
/// anything it cannot decode, on non-increasing time, or if there are none.
io::Log readLcmLog(const std::string& path, const std::string& channel = "PLSA_STATE");

/// Writes a log with the standard columns as actuator-state messages.
void writeLcmLog(const std::string& path, const io::Log& log, const std::string& channel = "PLSA_STATE");

/// Reads `path` by its extension: .lcmlog / .lcm as an LCM event log, else CSV.
io::Log readLogFile(const std::string& path, const io::CsvReadOptions& options = {});

}  // namespace plsa::lcm
