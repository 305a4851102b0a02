#pragma once

// The circle's constant and the degree in radians, for the simulators' sources.
namespace plsa::sim {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kDeg = kPi / 180.0;

}  // namespace plsa::sim
