// LCM event logs (the lcm-logger format) as plsa logs: actuator-state
// messages become rows with the standard column names, so every tool that
// reads CSV also reads a recording. The reader is plsa's own, bounded one:
// every length in the file is checked against its limit and against what is
// left before anything is allocated (liblcm's reader trusts them).
#pragma once

#include <cstdint>
#include <istream>
#include <string>

#include "plsa/io/csv_log.hpp"
#include "plsa/io/log_readers.hpp"

namespace plsa::lcm {

/// The word every event of an LCM log starts with (big-endian), so also the
/// file's first four bytes: how a log is recognised, whatever its name.
inline constexpr std::uint32_t kLcmLogSyncWord = 0xEDA1DA01u;
/// Longest channel name read (LCM itself allows 63 bytes).
inline constexpr std::int32_t kMaxChannelBytes = 255;

/// Reads the actuator-state messages on `channel`. Other channels are skipped
/// without being read into memory (and counted in the log's metadata). Throws
/// std::runtime_error naming the file, event and byte offset on anything it
/// cannot decode, on non-increasing time, or if there are none. A log that
/// ends inside an event (a recording cut short) keeps the events before it
/// and says so in Log::warnings.
io::Log readLcmLog(const std::string& path, const std::string& channel = "PLSA_STATE");
/// The same from a stream; `source` names it in messages.
io::Log readLcmLog(std::istream& in, const std::string& source, const std::string& channel = "PLSA_STATE");

/// Writes a log with the standard columns as actuator-state messages, atomically.
void writeLcmLog(const std::string& path, const io::Log& log, const std::string& channel = "PLSA_STATE");

/// Whether the file starts with the LCM sync word.
bool isLcmLog(const std::string& path);

/// Most bytes read from a log that is not a regular file (a pipe is read whole).
inline constexpr std::size_t kMaxPipedLogBytes = io::kMaxPipedLogBytes;

/// Reads `path` as an LCM event log when it starts with the sync word
/// (lcm-logger's names, such as lcmlog-2026-11-25.00, have no extension),
/// else as CSV.
io::Log readLogFile(const std::string& path, const io::CsvReadOptions& options = {});

/// The LCM event log as a log format: known by its sync word (and .lcmlog),
/// read on ReadOptions::lcm_channel (every required column checked), written
/// on WriteOptions::lcm_channel.
io::LogFormat lcmLogFormat();
/// Puts lcmLogFormat() in `registry` in place of the placeholder a build
/// without LCM has there (so repeating it changes nothing). Call it once at
/// start-up where LCM logs are to be read: it is not done by a static
/// initialiser, which the linker drops from a static library.
void registerLogFormats(io::LogReaderRegistry& registry = io::logReaders());

}  // namespace plsa::lcm
