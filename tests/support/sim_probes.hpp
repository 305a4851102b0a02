// Probes of the simulated actuator shared by its tests: configurations with
// every effect off or one on, held commands, settled bends, rise times and
// an up-and-down staircase.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "plsa/sim/actuator.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::sim::probes {

/// Every effect switched off; the sensor's noise as configured.
inline SimConfig everyEffectOff() {
  SimConfig c;
  for (const auto& e : effectNames()) c.setEffectEnabled(e, false);
  return c;
}

/// Every effect off and a noiseless sensor.
inline SimConfig allOff() {
  SimConfig c = everyEffectOff();
  c.sensor.noise_deg = 0.0;
  return c;
}

inline SimConfig only(const std::string& effect) {
  SimConfig c = allOff();
  c.setEffectEnabled(effect, true);
  return c;
}

// Holds a command for `seconds`, returns the samples.
inline std::vector<ActuatorSample> hold(Actuator& a, std::array<double, 3> cmd, double seconds) {
  std::vector<ActuatorSample> out;
  const int n = static_cast<int>(std::lround(seconds * a.config().sample_rate_hz));
  for (int k = 0; k < n; ++k) out.push_back(a.step(cmd));
  return out;
}

inline double settled(Actuator& a, std::array<double, 3> cmd, double seconds = 5.0) {
  return hold(a, cmd, seconds).back().true_bend_deg;
}

// 10-90% rise time of a local step response, judged against the bend 1.5 s
// after the step (the local response; creep keeps drifting after that).
inline double riseTime(Actuator& a, double from, double to) {
  const double start = settled(a, {from, 0, 0}, 8.0);
  const auto r = hold(a, {to, 0, 0}, 1.5);
  const double end = r.back().true_bend_deg;
  int t10 = -1, t90 = -1;
  for (int k = 0; k < static_cast<int>(r.size()); ++k) {
    const double frac = (r[static_cast<std::size_t>(k)].true_bend_deg - start) / (end - start);
    if (t10 < 0 && frac >= 0.1) t10 = k;
    if (t90 < 0 && frac >= 0.9) t90 = k;
  }
  return (t90 - t10) / a.config().sample_rate_hz;
}

// Up and down staircase on chamber 1; bend settled at `probe` bar on each way.
inline std::pair<double, double> upDownAt(const SimConfig& c, double probe) {
  Actuator a(c, 1);
  double up = 0, down = 0;
  for (int k = 1; k <= 14; ++k) {
    const double p = 0.025 * k;
    const double b = settled(a, {p, 0, 0}, 4.0);
    if (std::abs(p - probe) < 1e-9) up = b;
  }
  for (int k = 13; k >= 0; --k) {
    const double p = 0.025 * k;
    const double b = settled(a, {p, 0, 0}, 4.0);
    if (std::abs(p - probe) < 1e-9) down = b;
  }
  return {up, down};
}

}  // namespace plsa::sim::probes
