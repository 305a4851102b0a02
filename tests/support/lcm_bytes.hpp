// LCM messages as bytes for tests that hand nodes and decoders what an
// attacker or a broken peer would: a message encoded, then a count patched.
#pragma once

#include <cstdint>
#include <string>

#include <plsa_lcm/actuator_state_t.hpp>

namespace plsa::test {

/// The generated encoder's bytes for `m`.
template <class Message>
std::string encoded(const Message& m) {
  std::string b(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

/// `bytes` with a big-endian 32-bit value written at `at` (an LCM count or length).
inline std::string withInt32(std::string bytes, std::size_t at, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) bytes[at + static_cast<std::size_t>(i)] = static_cast<char>(value >> (24 - 8 * i));
  return bytes;
}

/// A plausible actuator state: `chambers` chambers at 0.2 bar, 10 deg bent.
inline plsa_lcm::actuator_state_t stateMessage(std::int64_t utime, std::int64_t seq, std::int32_t chambers = 3) {
  plsa_lcm::actuator_state_t s{};
  s.utime = utime;
  s.seq = seq;
  s.n_chambers = chambers;
  s.command_bar.assign(static_cast<std::size_t>(chambers), 0.2);
  s.pressure_bar.assign(static_cast<std::size_t>(chambers), 0.2);
  s.bend_deg = 10;
  s.steer_deg = 30;
  for (auto& row : s.sensor_rotation)
    for (double& v : row) v = 0;
  s.vented = 0;
  return s;
}

}  // namespace plsa::test
