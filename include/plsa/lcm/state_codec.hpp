// Conversions between simulator samples, log rows and the LCM actuator state.
#pragma once

#include <cstdint>

#include <plsa_lcm/actuator_state_t.hpp>

#include "plsa/sim/actuator.hpp"

namespace plsa::lcm {

plsa_lcm::actuator_state_t toMessage(const sim::ActuatorSample& s, std::int64_t seq, bool vented);

/// The standard log columns of a state message, in order:
/// time_s, cmd_1..3, p_1..3, bend_deg, steer_deg. Throws if it has not 3 chambers.
void toRow(const plsa_lcm::actuator_state_t& m, double row[9]);

}  // namespace plsa::lcm
