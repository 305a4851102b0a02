#pragma once

// The circle's constant and the degree in radians: the one definition of each
// that the output frame, the predictor's tip angles and the simulators share.
namespace plsa {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadPerDeg = kPi / 180.0;

}  // namespace plsa
