// Conversions between simulator samples, log rows and the LCM actuator state.
#pragma once

#include <cstdint>

#include <plsa_lcm/actuator_state_t.hpp>

#include "plsa/sim/actuator.hpp"

namespace plsa::lcm {

/// Microseconds since the Unix epoch, now, on the system clock: the time base
/// of every plsa message's utime.
std::int64_t epochMicroseconds();

/// A simulator sample as a state message stamped utime = `origin_us` + its
/// simulated time: with the epoch time at which the simulation started, the
/// state sits on the same time line as every other message (a log converted
/// from CSV keeps its own origin, 0 by default).
plsa_lcm::actuator_state_t toMessage(const sim::ActuatorSample& s, std::int64_t seq, bool vented,
                                     std::int64_t origin_us = 0);

/// The largest |utime| a log row takes: 2^53 microseconds (285 years), below
/// which seconds as a double keep every microsecond (at 2^63 they step by 1 ms,
/// and an 80 Hz log reads as irregular).
inline constexpr std::int64_t kMaxLogUtime = std::int64_t{1} << 53;

/// The standard log columns of a state message, in order:
/// time_s, cmd_1..3, p_1..3, bend_deg, steer_deg. Throws if it has not 3
/// chambers, or a utime beyond kMaxLogUtime.
void toRow(const plsa_lcm::actuator_state_t& m, double row[9]);

}  // namespace plsa::lcm
