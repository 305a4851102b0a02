// Checked decoding of plsa's LCM messages. lcm-gen's decoders trust the
// counts and lengths in the bytes: a negative count throws from
// std::vector::resize, a huge one allocates gigabytes, and a length check that
// overflows an int reads past the buffer. These walk the bytes first, check
// the type's fingerprint, every count against its limit and every length
// against what is left, and only then let the generated decoder fill the
// message. Every node that subscribes uses them; nothing else decodes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <plsa_lcm/actuator_state_t.hpp>
#include <plsa_lcm/prediction_t.hpp>
#include <plsa_lcm/pressure_command_t.hpp>
#include <plsa_lcm/status_t.hpp>

namespace plsa::lcm {

/// Limits on what a message may carry (docs/robustness.md). Counts beyond
/// them are refused before anything is allocated.
inline constexpr std::int32_t kMaxChambers = 16;             ///< n_chambers
inline constexpr std::int32_t kMaxPredictionSteps = 100000;  ///< prediction_t.horizon
inline constexpr std::int32_t kMaxPredictionOutputs = 64;    ///< prediction_t.n_outputs
inline constexpr std::int32_t kMaxStatusValues = 1024;       ///< status_t.n_values
inline constexpr std::int32_t kMaxStringBytes = 4096;        ///< any string, with its terminating NUL
/// Largest message accepted at all (a 100000-step, 64-output prediction is 51 MB).
inline constexpr std::size_t kMaxMessageBytes = std::size_t{64} << 20;

/// Each fills `out` and returns an empty string when `data[0, size)` is
/// exactly one message of the type; otherwise leaves `out` unspecified and
/// returns why, naming the field ("n_chambers = -1 is outside 0..16").
/// Nothing is allocated before the counts have been checked.
std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::pressure_command_t& out);
std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::actuator_state_t& out);
std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::prediction_t& out);
std::string decodeMessage(const void* data, std::size_t size, plsa_lcm::status_t& out);

}  // namespace plsa::lcm
