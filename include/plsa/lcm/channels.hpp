// Default LCM channel names shared by plsa's nodes and tools.
#pragma once

namespace plsa::lcm {

inline constexpr const char* kStateChannel = "PLSA_STATE";
inline constexpr const char* kCommandChannel = "PLSA_COMMAND";
inline constexpr const char* kPredictionChannel = "PLSA_PREDICTION";
inline constexpr const char* kStatusChannel = "PLSA_STATUS";

}  // namespace plsa::lcm
