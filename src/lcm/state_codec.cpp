#include "plsa/lcm/state_codec.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

namespace plsa::lcm {

std::int64_t epochMicroseconds() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

plsa_lcm::actuator_state_t toMessage(const sim::ActuatorSample& s, std::int64_t seq, bool vented,
                                     std::int64_t origin_us) {
  plsa_lcm::actuator_state_t m;
  m.utime = origin_us + static_cast<std::int64_t>(std::llround(s.time_s * 1e6));
  m.seq = seq;
  m.n_chambers = 3;
  m.command_bar.assign(s.command_bar.begin(), s.command_bar.end());
  m.pressure_bar.assign(s.pressure_bar.begin(), s.pressure_bar.end());
  m.bend_deg = s.bend_deg;
  m.steer_deg = s.steer_deg;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.sensor_rotation[r][c] = s.sensor_rotation(r, c);
  m.vented = vented ? 1 : 0;
  return m;
}

void toRow(const plsa_lcm::actuator_state_t& m, double row[9]) {
  if (m.n_chambers != 3 || m.command_bar.size() != 3 || m.pressure_bar.size() != 3)
    throw std::invalid_argument("actuator state has " + std::to_string(m.n_chambers) +
                                " chambers; the standard columns need 3");
  if (m.utime > kMaxLogUtime || m.utime < -kMaxLogUtime)
    throw std::invalid_argument("utime " + std::to_string(m.utime) +
                                " us is beyond 2^53 us (285 years), where time in seconds loses microseconds");
  row[0] = static_cast<double>(m.utime) * 1e-6;
  for (int i = 0; i < 3; ++i) {
    row[1 + i] = m.command_bar[static_cast<std::size_t>(i)];
    row[4 + i] = m.pressure_bar[static_cast<std::size_t>(i)];
  }
  row[7] = m.bend_deg;
  row[8] = m.steer_deg;
}

}  // namespace plsa::lcm
