// Signal maps as DBC files (Vector's CAN database text format), the way CAN
// buses are described in most tools: `BO_` messages and their `SG_` signals
// read into a SignalMap and written from one (docs/can.md, "DBC files").
// plsa's signals are byte-aligned 8-, 16- or 32-bit integers; a DBC signal
// named `counter` or `checksum` (8 bits, unsigned, scale 1, offset 0) is the
// message's rolling counter or checksum byte. DBC cannot say how a checksum
// is computed: plsa's is (id low byte + id high byte + every other data
// byte) mod 256, and a bus that computes another one cannot be read.
#pragma once

#include <string>

#include "plsa/can/signal_map.hpp"

namespace plsa::can {

/// Largest DBC file read (a bus's database is rarely over a megabyte).
inline constexpr std::size_t kMaxDbcBytes = std::size_t{16} << 20;

/// Reads the messages and signals of a DBC text. Throws std::invalid_argument
/// naming the source, line and field for what a signal map cannot carry
/// (extended ids, multiplexed, float or non-byte-aligned signals, widths
/// other than 8, 16 and 32 bits) and for malformed lines; the map is
/// validated as a JSON one is. `profile` names it.
SignalMap signalMapFromDbc(const std::string& text, const std::string& source, const std::string& profile);

/// The map as DBC text (one node, `plsa`, sends and receives everything);
/// signalMapFromDbc reads it back to the same map.
std::string signalMapToDbc(const SignalMap& map);

/// The map as plsa's JSON profile (schemas/signal-map.schema.json).
std::string signalMapToJson(const SignalMap& map);

}  // namespace plsa::can
