// Bus recordings made with can-utils' candump (`candump -l`, or `-L` to
// standard output) as logs every tool reads: each line a frame,
// `(seconds.micros) interface id#data`, decoded with a signal map (the
// driver's messages: valve_command, pressure_sensor and, if present,
// tip_angle) and laid on a uniform grid at the pressure sensors' rate, each
// row one bus cycle holding the latest value of every signal (docs/can.md,
// "Bus logs").
#pragma once

#include <cstddef>
#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include "plsa/can/signal_map.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/io/log_readers.hpp"

namespace plsa::can {

/// Longest candump line taken (a classic frame's line is under 60 bytes).
inline constexpr std::size_t kMaxCandumpLineBytes = 256;
/// Most frames of the profile's messages one log may hold (about 5 h of the
/// three driver messages at 80 Hz).
inline constexpr std::size_t kMaxCandumpFrames = std::size_t{5} << 20;

/// One line of a candump log. Frames plsa cannot map (extended ids, remote
/// and CAN FD frames) keep their kind and no data.
struct CandumpLine {
  enum class Kind { kClassic, kExtended, kRemote, kFd };
  double time_s = 0.0;  ///< the time stamp as written (seconds, usually since 1970)
  std::string interface;
  Kind kind = Kind::kClassic;
  CanFrame frame;  ///< kClassic only: id, dlc, data
};

/// Parses one line (without its newline). Throws std::runtime_error
/// "SOURCE:LINE: reason" for anything that is not a candump log line.
CandumpLine parseCandumpLine(const std::string& line, const std::string& source, std::size_t line_number);

/// One frame as a candump -l line, "(time) interface ID#DATA\n" (six
/// decimals, the id's three hex digits, the data's DLC bytes in hex).
std::string candumpLine(double time_s, const std::string& interface, const CanFrame& frame);

/// Whether `head` (a file's first bytes) starts like a candump log.
bool looksLikeCandump(const std::string& head);

/// Reads a candump log into a log with plsa's recorded columns: time_s (from
/// 0 at the first row), cmd_1.. (valve_command), p_1.. (pressure_sensor),
/// bend_deg and steer_deg (tip_angle), one row per bus cycle of the pressure
/// sensors (the median interval dt of their frames), each row holding every
/// signal's latest frame before the cycle ends (dt / 2 after the sensor's
/// time), from the first cycle in which every message present has been
/// seen. Frames with a bad length or checksum are
/// dropped; counter gaps, dropped frames, unknown ids, other frame kinds,
/// several interfaces and gaps in the sensor frames are counted in
/// Log::warnings; the counts and the start time are in Log::metadata.
/// Throws std::runtime_error naming the source (and line) when the log is not
/// candump text, is out of time order, or has too few pressure frames.
io::Log readCandumpLog(std::istream& in, const std::string& source, const SignalMap& map);

/// A log as candump -l text: per row, at its time_s (seconds, six decimals),
/// the valve_command, pressure_sensor and tip_angle frames of `map` whose
/// columns the log has (p_1.. required), encoded on interface can0 with
/// their counters and checksums: what canplayer replays on a bus, and what
/// readCandumpLog reads back (to the signals' resolution). Throws
/// std::invalid_argument naming the row, message and value a signal cannot
/// carry; written atomically.
void writeCandumpLog(const std::string& path, const io::Log& log, const SignalMap& map);

/// The candump format for a log registry: known by its first line's shape
/// and by `.candump`; frames decoded and encoded with the signal map file in
/// ReadOptions::can_profile / WriteOptions::can_profile, or the default
/// profile when that is empty.
io::LogFormat candumpLogFormat();

/// Adds candumpLogFormat() to a registry (plsa's tools call it at start).
void registerLogFormats(io::LogReaderRegistry& registry = io::logReaders());

}  // namespace plsa::can
