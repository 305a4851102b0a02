// CAN frame layouts as data: a signal map (JSON) names each message's id,
// length, byte-aligned signals (offset, bits, endianness, scale, offset,
// unit, sign) and optional rolling counter and checksum bytes. Decoding
// checks length, checksum and counter continuity, and never allocates.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "plsa/can/can_transport.hpp"

namespace plsa::can {

struct Signal {
  std::string name;
  int byte = 0;   ///< first byte
  int bits = 16;  ///< 8, 16 or 32
  bool little_endian = true;
  bool is_signed = false;
  double scale = 1.0;  ///< physical = raw * scale + offset
  double offset = 0.0;
  std::string unit;
};

/// The physical values a signal's raw field can carry, [lo, hi].
struct PhysicalRange {
  double lo = 0.0, hi = 0.0;
};
PhysicalRange physicalRange(const Signal& s) noexcept;

struct MessageLayout {
  static constexpr int kMaxSignals = 8;
  std::string name;
  std::uint32_t id = 0;
  int dlc = 8;
  int counter_byte = -1;   ///< -1: none; a byte that increases by 1 (mod 256) per frame
  int checksum_byte = -1;  ///< -1: none; (id low + id high + every other byte) mod 256
  std::vector<Signal> signals;
};

/// Why a frame was rejected (kOk: accepted).
enum class DecodeStatus { kOk, kWrongId, kWrongLength, kBadChecksum, kCounterGap };
const char* toString(DecodeStatus s);

struct SignalMap {
  std::string profile;
  std::vector<MessageLayout> messages;

  const MessageLayout& message(const std::string& name) const;        ///< throws naming the known ones
  const MessageLayout* find(const std::string& name) const noexcept;  ///< nullptr when absent
  /// Throws std::invalid_argument naming the message and field at fault
  /// (overlaps, bytes beyond the DLC, bad widths, ids above 11 bits).
  void validate() const;
};

/// Most messages a signal map may describe.
inline constexpr std::size_t kMaxMessages = 64;

/// Parses a profile: unknown and duplicate keys, duplicate message names, ids
/// or signal names, and out-of-range numbers are errors naming the source and field.
SignalMap signalMapFromJson(const std::string& text, const std::string& source = "<json>");
/// A profile file: a DBC file (`.dbc`, can/dbc.hpp; the profile named by the
/// file's stem) or plsa's JSON.
SignalMap loadSignalMap(const std::string& path);
/// What a valve/sensor profile allows that the driver cannot guard against:
/// no counter or checksum on a message it reads or writes, signals in an order
/// or unit other than the documented ones (they are taken by position).
/// Empty for the default profile. Tools print these before they start.
std::vector<std::string> driverProfileWarnings(const SignalMap& map);

/// The documented default profile (docs/can.md): valves 0x100, sensors 0x200.
SignalMap defaultSignalMap();

/// Encodes physical values (one per signal, in order) with a counter value.
/// Returns false if a value does not fit the signal's raw range.
bool encodeFrame(const MessageLayout& m, const double* values, std::uint8_t counter, CanFrame& out) noexcept;

/// Decodes into values (one per signal). `last_counter` carries the counter
/// between calls (-1: none seen yet); a gap is reported after the values are
/// written (the frame itself is intact, one was lost before it).
DecodeStatus decodeFrame(const MessageLayout& m, const CanFrame& f, double* values, int& last_counter) noexcept;

}  // namespace plsa::can
