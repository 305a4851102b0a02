#include "plsa/sim/actuator.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "plsa/core/angle_units.hpp"

namespace plsa::sim {
namespace {

// Prandtl-Ishlinskii formulation: this many play operators, widths spread to 2x.
constexpr int kPiOperators = 5;

Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }
Eigen::Matrix3d rotY(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

double softplus(double x) { return x > 30 ? x : std::log1p(std::exp(x)); }

// The exact step of x'' = -w^2 x - 2 zeta w x' over h: exp(A h) for
// A = [0 1; -w^2 -2 zeta w], as (x from x, x from x', x' from x, x' from x').
// exp(A h) = C I + S (A + a I), a = zeta w, with C = e^(-a h) cos(s h) and
// S = e^(-a h) sin(s h) / s (s = w sqrt(|1 - zeta^2|)); overdamped, the
// hyperbolic ones, taken from the slower eigenvalue -a + s so that neither
// overflows (e^(-a h) cosh(s h) of a stiff step would be 0 times inf); at
// critical damping e^(-a h) and h e^(-a h).
std::array<double, 4> dampedTransition(double omega, double zeta, double h) {
  const double a = zeta * omega, split = 1.0 - zeta * zeta, s = omega * std::sqrt(std::abs(split));
  if (split < 0.0 && s * h > 1e-6) {
    const double slow = std::exp((s - a) * h);  // e^(-a h) e^(s h)
    const double c = 0.5 * slow * (1.0 + std::exp(-2.0 * s * h)), sine = -0.5 * slow * std::expm1(-2.0 * s * h) / s;
    return {c + a * sine, sine, -omega * omega * sine, c - a * sine};
  }
  double c = 1.0, sine_over_s = h;
  if (s * h > 1e-6) {
    c = std::cos(s * h);
    sine_over_s = std::sin(s * h) / s;
  }
  const double decay = std::exp(-a * h);
  return {decay * (c + a * sine_over_s), decay * sine_over_s, -decay * omega * omega * sine_over_s,
          decay * (c - a * sine_over_s)};
}

// The share of its distance to a held source a first-order part covers in h.
double reachIn(double h, double time_constant_s) { return -std::expm1(-h / time_constant_s); }

}  // namespace

void anglesFromRotation(const Eigen::Matrix3d& b_a_g, double& bend_deg, double& steer_deg) {
  // (5): theta_d = acos(<e_x, B_A_G e_Z>); (6): phi = atan2(<e_x, R e_Y>, <e_x, R e_X>).
  const double c = std::clamp(b_a_g(0, 2), -1.0, 1.0);
  bend_deg = std::acos(c) / kRadPerDeg;
  steer_deg = std::atan2(b_a_g(0, 1), b_a_g(0, 0)) / kRadPerDeg;
}

Subspace configurationSubspace(const SimConfig::Geometry& g, double steer_deg) {
  for (int i = 0; i < 3; ++i) {
    const double start = g.bend_direction_deg[static_cast<std::size_t>(i)];
    const double end = g.bend_direction_deg[static_cast<std::size_t>((i + 1) % 3)];
    const double span = std::fmod(end - start + 720.0, 360.0);
    const double rel = std::fmod(steer_deg - start + 720.0, 360.0);
    if (rel < span || (i == 2 && rel <= span)) return {i + 1, rel};
  }
  return {1, std::fmod(steer_deg - g.bend_direction_deg[0] + 720.0, 360.0)};
}

Eigen::Vector3d tipPosition(double arc_length_m, double bend_rad, double steer_rad) {
  if (std::abs(bend_rad) < 1e-9) return {0.0, 0.0, arc_length_m};
  const double kappa = bend_rad / arc_length_m;
  const double r = (1.0 - std::cos(bend_rad)) / kappa;
  return {r * std::cos(steer_rad), r * std::sin(steer_rad), std::sin(bend_rad) / kappa};
}

Actuator::Actuator(const SimConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  config_.validate();
  const double period = 1.0 / config_.sample_rate_hz;
  substeps_ = std::max(1, static_cast<int>(std::lround(period / config_.internal_step_s)));
  dt_ = period / substeps_;
  const std::string& hyst = config_.hysteresis.formulation;
  // weighted_pi: three plays, then the smooth element's z and the strain it last saw.
  constexpr std::size_t kWeightedPiStates = 5;
  const std::size_t n_play = hyst == "prandtl_ishlinskii" ? kPiOperators
                             : hyst == "weighted_pi"      ? kWeightedPiStates
                                                          : 1;
  weighted_pi_ = hyst == "weighted_pi";
  if (weighted_pi_) {
    const auto& h = config_.hysteresis;
    pi_weights_ = {h.weight_narrow, h.weight_mid, h.weight_wide, h.weight_smooth};
    const double p = config_.max_pressure_bar;
    full_strain_ = std::abs(config_.elongation.strain_per_bar * p + config_.elongation.quadratic * p * p);
    double sum = 0.0;
    for (double w : pi_weights_) sum += std::abs(w);
    if (sum > 1.0)
      for (double& w : pi_weights_) w /= sum;
  }
  for (auto& p : play_) p.assign(n_play, 0.0);
  // A fractional delay (linear between two taps) keeps the response, and so
  // any calibration of delay_s, continuous in the parameter.
  const double delay_steps = config_.pneumatic_lag.enabled ? config_.pneumatic_lag.delay_s / dt_ : 0.0;
  delay_whole_ = static_cast<std::size_t>(std::floor(delay_steps));
  delay_frac_ = delay_steps - static_cast<double>(delay_whole_);
  delay_line_.assign(delay_whole_ + 2, {0.0, 0.0, 0.0});
  const std::string& flow = config_.pneumatic_lag.formulation;
  flow_law_ = flow == "orifice"  ? FlowLaw::kOrifice
              : flow == "choked" ? FlowLaw::kChoked
              : flow == "power"  ? FlowLaw::kPower
                                 : FlowLaw::kLinear;
  const double line_tau = config_.pneumatic_lag.line_time_constant_s;
  if (config_.pneumatic_lag.enabled && flow_law_ == FlowLaw::kPower && line_tau > 0.0)
    line_blend_ = -std::expm1(-dt_ / line_tau);
  power_log_gain_fill_ = std::log(0.1 / config_.pneumatic_lag.fill_time_constant_s);
  power_log_gain_vent_ = std::log(0.1 / config_.pneumatic_lag.vent_time_constant_s);
  const std::string& stiff = config_.stiffening.formulation;
  stiffening_law_ = stiff == "quadratic"     ? StiffeningLaw::kQuadratic
                    : stiff == "exponential" ? StiffeningLaw::kExponential
                    : stiff == "power"       ? StiffeningLaw::kPower
                                             : StiffeningLaw::kLinear;
  saturating_coupling_ = config_.coupling.formulation == "saturating";
  two_rate_creep_ = config_.creep.formulation == "two_rate";
  random_walk_bias_ = config_.sensor_bias.formulation == "random_walk";
  smooth_deadzone_ = config_.deadzone.formulation == "smooth";
  const double tilt = config_.sensor_bias.enabled ? config_.sensor_bias.tilt_deg * kRadPerDeg : 0.0;
  tilted_x_axis_ = {std::cos(tilt - kPi / 2.0), -std::sin(tilt - kPi / 2.0)};
  lever_ = 2.0 * config_.geometry.length_m / (3.0 * config_.geometry.chamber_radius_m);
  omega_ = 2.0 * kPi * config_.bending.natural_freq_hz;
  const double zeta = config_.bending.damping_ratio;
  piece_limit_ = std::sqrt(4.0 * zeta * zeta + 2.0) - 2.0 * zeta;  // the root of a^2 + 4 zeta a = 2
  exponential_ = config_.integrator == "exponential";
  const auto& lag = config_.pneumatic_lag;
  linear_flow_ = !lag.enabled || flow_law_ == FlowLaw::kLinear;
  reach_fill_ = reachIn(dt_, lag.enabled ? lag.fill_time_constant_s : config_.pneumatics.time_constant_s);
  reach_vent_ = reachIn(dt_, lag.enabled ? lag.vent_time_constant_s : config_.pneumatics.time_constant_s);
  reach_creep_ = reachIn(dt_, config_.creep.time_constant_s);
  reach_creep_fast_ = reachIn(dt_, 0.2 * config_.creep.time_constant_s);
  reach_creep_slow_ = reachIn(dt_, 2.0 * config_.creep.time_constant_s);
  bend_transition_ = dampedTransition(omega_, zeta, dt_);
  for (std::size_t i = 0; i < 3; ++i) {
    const double dir = config_.geometry.bend_direction_deg[i] * kRadPerDeg;
    bend_direction_[i] = {std::cos(dir), std::sin(dir)};
  }
}

double Actuator::smoothEffectivePressure(double p) const {
  const auto& dz = config_.deadzone;
  const double w = dz.smooth_width_bar;
  return w * (softplus((p - dz.threshold_bar) / w) - softplus(-dz.threshold_bar / w));
}

// Transport delay: a ring of past commands, one per internal step, read
// between two taps.
std::array<double, 3> Actuator::delayedCommand(const std::array<double, 3>& cmd) {
  if (delay_whole_ == 0 && delay_frac_ == 0.0) return cmd;  // no delay: the blend below is cmd exactly
  // The ring's indices wrap by comparison: no integer division in a substep.
  const std::size_t size = delay_line_.size();  // delay_whole_ + 2
  delay_line_[delay_head_] = cmd;
  const std::size_t at = delay_head_ >= delay_whole_ ? delay_head_ - delay_whole_ : delay_head_ + size - delay_whole_;
  const auto& newer = delay_line_[at];
  const auto& older = delay_line_[at == 0 ? size - 1 : at - 1];
  delay_head_ = delay_head_ + 1 == size ? 0 : delay_head_ + 1;
  std::array<double, 3> delayed{};
  for (std::size_t i = 0; i < 3; ++i) delayed[i] = (1.0 - delay_frac_) * newer[i] + delay_frac_ * older[i];
  return delayed;
}

// The power flow law's rate of pressure change (bar/s) for a pressure
// difference `drive` toward a source above (`filling`) or below the
// chamber's pressure p: 0.1 bar (|drive| / 0.1 bar)^exponent /
// (tau e^(pressure_per_bar p)), signed as drive, with tau the fill or vent
// time constant. As one exponential of a sum of logarithms, the time
// constants' taken once: every internal step of a kept or candidate lag
// takes three of these, and pow and exp took a fifth of a diagnosis's time.
double Actuator::powerLawRate(double drive, bool filling, double p) const {
  if (drive == 0.0) return 0.0;
  const auto& lag = config_.pneumatic_lag;
  const double log_gain = filling ? power_log_gain_fill_ : power_log_gain_vent_;
  return std::copysign(std::exp(lag.exponent * std::log(std::abs(drive) * 10.0) - lag.pressure_per_bar * p + log_gain),
                       drive);
}

// Each chamber's pressure one step toward the delayed command (through its
// supply line first, when it has one), rate-limited; returns the pressures
// past the deadzone.
std::array<double, 3> Actuator::fillChambers(const std::array<double, 3>& delayed) {
  const SimConfig& c = config_;
  const bool lag = c.pneumatic_lag.enabled;
  const double max_rate = c.pneumatics.max_rate_bar_per_s;
  std::array<double, 3> p_eff{};
  for (std::size_t i = 0; i < 3; ++i) {
    double source = delayed[i];
    if (line_blend_ > 0.0) source = line_pressure_[i] += (delayed[i] - line_pressure_[i]) * line_blend_;
    const bool filling = source > pressure_[i];
    const double tau = lag ? (filling ? c.pneumatic_lag.fill_time_constant_s : c.pneumatic_lag.vent_time_constant_s)
                           : c.pneumatics.time_constant_s;
    const double gap = source - pressure_[i];
    double drive = gap;
    double rate = 0.0;
    if (lag && flow_law_ == FlowLaw::kPower) {
      rate = powerLawRate(drive, filling, pressure_[i]);
    } else {
      // Laws equal to the linear one at a 0.1 bar difference (choked: below 0.05 bar).
      if (lag && flow_law_ == FlowLaw::kOrifice) drive = std::copysign(std::sqrt(std::abs(drive) * 0.1), drive);
      if (lag && flow_law_ == FlowLaw::kChoked) drive = std::clamp(drive, -0.05, 0.05);
      rate = drive / tau;
    }
    pressure_[i] += exponential_ ? chamberChange(gap, rate, filling) : std::clamp(rate, -max_rate, max_rate) * dt_;
    p_eff[i] = effectivePressure(pressure_[i]);
  }
  return p_eff;
}

// The exponential integrator's chamber step: the linear law's exact one; a
// nonlinear law's at the time constant its rate has at the step's start
// (gap / rate), which neither overshoots the source nor rings at a long
// step; then the flow limit.
double Actuator::chamberChange(double gap, double rate, bool filling) const {
  const double limit = config_.pneumatics.max_rate_bar_per_s * dt_;
  double change = 0.0;
  if (linear_flow_)
    change = gap * (filling ? reach_fill_ : reach_vent_);
  else if (gap != 0.0)
    change = -gap * std::expm1(-rate / gap * dt_);
  return std::clamp(change, -limit, limit);
}

// A chamber's strain through its play operators, when hysteresis is on.
double Actuator::hysteresisStrain(std::size_t chamber, double strain) {
  const SimConfig::Hysteresis& h = config_.hysteresis;
  auto& plays = play_[chamber];
  if (weighted_pi_) {
    const double share = h.fixed_band_share;
    const double band = (1.0 - share) * std::abs(strain) + share * full_strain_;
    double out = strain;
    for (std::size_t k = 0; k < 3; ++k) {
      const double r = h.width * (k == 0 ? 0.5 : k == 1 ? 1.0 : 2.0) * band;
      plays[k] = std::clamp(plays[k], strain - r, strain + r);
      out += pi_weights_[k] * (plays[k] - strain);
    }
    if (pi_weights_[3] != 0.0) out += pi_weights_[3] * (smoothElement(plays[3], plays[4], strain) - strain);
    return out;
  }
  // Play operator(s): output moves only once the input leaves a band around it.
  double out = 0.0;
  for (std::size_t k = 0; k < plays.size(); ++k) {
    // Band proportional to the strain, so the loop closes at zero and at the peak.
    const double w = plays.size() == 1
                         ? h.width
                         : h.width * 2.0 * static_cast<double>(k + 1) / static_cast<double>(plays.size() + 1);
    const double r = w * std::abs(strain);
    plays[k] = std::clamp(plays[k], strain - r, strain + r);
    out += plays[k];
  }
  return out / static_cast<double>(plays.size());
}

// The weighted-PI law's smooth element one step on: z follows the strain
// and saturates at smooth_saturation times the strain at full pressure,
// unloading steeper or shallower by smooth_asymmetry (Bouc-Wen, exponent 1).
double Actuator::smoothElement(double& z, double& last_strain, double strain) const {
  const SimConfig::Hysteresis& h = config_.hysteresis;
  const double bound = std::max(h.smooth_saturation * full_strain_, 1e-12);
  const double beta = 0.5 * (1.0 + h.smooth_asymmetry) / bound, gamma = 0.5 * (1.0 - h.smooth_asymmetry) / bound;
  const double ds = strain - last_strain;
  last_strain = strain;
  z += ds - (beta * std::abs(ds) * z + gamma * ds * std::abs(z));
  z = std::clamp(z, -bound, bound);  // a step longer than the bound cannot overshoot it
  return z;
}

// A chamber's strain with its creep (one or two first-order lags) added.
double Actuator::creepStrain(std::size_t i, double strain) {
  const SimConfig::Creep& c = config_.creep;
  if (two_rate_creep_) {
    if (exponential_) {
      creep_[i] += (0.5 * c.fraction * strain - creep_[i]) * reach_creep_fast_;
      creep_slow_[i] += (0.5 * c.fraction * strain - creep_slow_[i]) * reach_creep_slow_;
    } else {
      creep_[i] += (0.5 * c.fraction * strain - creep_[i]) / (0.2 * c.time_constant_s) * dt_;
      creep_slow_[i] += (0.5 * c.fraction * strain - creep_slow_[i]) / (2.0 * c.time_constant_s) * dt_;
    }
    return strain + creep_[i] + creep_slow_[i];
  }
  if (exponential_)
    creep_[i] += (c.fraction * strain - creep_[i]) * reach_creep_;
  else
    creep_[i] += (c.fraction * strain - creep_[i]) / c.time_constant_s * dt_;
  return strain + creep_[i];
}

// The bending mode one step toward `target`, stiffened by the summed pressure.
void Actuator::bendToward(Eigen::Vector2d target, double sum_p) {
  const SimConfig& c = config_;
  double omega = omega_;
  if (c.stiffening.enabled) {
    // Every law is written against a 0.2 bar reference: per_bar means the same growth there.
    const double x = sum_p / 0.2;
    double growth = x;
    if (stiffening_law_ == StiffeningLaw::kQuadratic) growth = x * x;
    if (stiffening_law_ == StiffeningLaw::kExponential) growth = std::expm1(x) / (std::exp(1.0) - 1.0);
    // The power law's powers as exponentials of logarithms: pow took a
    // fifth of a stiffening candidate's calibration.
    if (stiffening_law_ == StiffeningLaw::kPower)
      growth = x > 0.0 ? std::exp(c.stiffening.exponent * std::log(x)) : 0.0;
    const double stiffer = 1.0 + c.stiffening.per_bar * 0.2 * growth;
    omega *= std::sqrt(stiffer);
    if (stiffening_law_ == StiffeningLaw::kPower && c.stiffening.static_share > 0.0)
      target *= std::exp(-c.stiffening.static_share * std::log(stiffer));
  }
  // Semi-implicit Euler on theta'' = w^2 (target - spring(theta)) - 2 zeta w theta',
  // spring(theta) = theta, or theta (1 + per_rad2 |theta|^2) for a hardening "power" stiffening.
  const bool hardening =
      c.stiffening.enabled && stiffening_law_ == StiffeningLaw::kPower && c.stiffening.per_rad2 > 0.0;
  if (exponential_ && !hardening) {
    bendExactly(target, omega);
    return;
  }
  const int pieces = bendingPieces(omega, hardening ? 1.0 + 3.0 * c.stiffening.per_rad2 * bend_.squaredNorm() : 1.0);
  const double h = dt_ / pieces;
  for (int k = 0; k < pieces; ++k) {
    Eigen::Vector2d spring = bend_;
    if (hardening) spring *= 1.0 + c.stiffening.per_rad2 * bend_.squaredNorm();
    bend_rate_ += (omega * omega * (target - spring) - 2.0 * c.bending.damping_ratio * omega * bend_rate_) * h;
    bend_ += bend_rate_ * h;
  }
}

// The exponential integrator's bending step: exact for the mode toward a
// target moving at a constant rate r over the step, from the last step's
// target to this one's (the chambers' pressures move through a step; a
// held target lags them by half a step). Against a moving target the mode
// settles 2 zeta r / w behind it: the distance u = theta - target + 2 zeta
// r / w and its rate u' = theta' - r are a free damped mode (the
// unstiffened one's transition taken once).
void Actuator::bendExactly(const Eigen::Vector2d& target, double omega) {
  const double zeta = config_.bending.damping_ratio;
  const std::array<double, 4> t = omega == omega_ ? bend_transition_ : dampedTransition(omega, zeta, dt_);
  const Eigen::Vector2d rate = (target - last_target_) / dt_, behind = 2.0 * zeta / omega * rate;
  const Eigen::Vector2d u = bend_ - last_target_ + behind, u_rate = bend_rate_ - rate;
  bend_ = target - behind + t[0] * u + t[1] * u_rate;
  bend_rate_ = rate + t[2] * u + t[3] * u_rate;
  last_target_ = target;
}

// The pieces one substep's bending is integrated in. Semi-implicit Euler on
// the damped oscillator is stable while a^2 + 4 zeta a < 4 (a = w dt, w the
// natural frequency with the spring's local stiffening `spring_slope`); a
// substep is split so that each piece keeps a^2 + 4 zeta a <= 2, so a
// segment stiffened far past its natural frequency (high pressures, a
// hardening spring) neither diverges nor rings. One piece wherever that
// holds at internal_step_s, so those runs are unchanged.
int Actuator::bendingPieces(double omega, double spring_slope) const {
  const double a = omega * (spring_slope == 1.0 ? 1.0 : std::sqrt(spring_slope)) * dt_;
  if (!(a > piece_limit_)) return 1;  // also a NaN: nothing to split
  return static_cast<int>(std::min(std::ceil(a / piece_limit_), static_cast<double>(kMaxBendingPieces)));
}

void Actuator::substep(const std::array<double, 3>& cmd) {
  const SimConfig& c = config_;
  const std::array<double, 3> p_eff = fillChambers(delayedCommand(cmd));
  const double sum_p = p_eff[0] + p_eff[1] + p_eff[2];
  Eigen::Vector2d target = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < 3; ++i) {
    double strain = c.elongation.strain_per_bar * p_eff[i] + c.elongation.quadratic * p_eff[i] * p_eff[i];
    if (c.coupling.enabled)
      strain *= saturating_coupling_ ? 1.0 / (1.0 + c.coupling.per_bar * (sum_p - p_eff[i]))
                                     : std::max(0.0, 1.0 - c.coupling.per_bar * (sum_p - p_eff[i]));
    if (c.hysteresis.enabled) strain = hysteresisStrain(i, strain);
    if (c.creep.enabled) strain = creepStrain(i, strain);
    // Constant-curvature map: a chamber's elongation bends the tip toward its bending direction.
    target += lever_ * strain * Eigen::Vector2d(bend_direction_[i][0], bend_direction_[i][1]);
  }
  bendToward(target, sum_p);
}

// The yaw the sensor reads at this sample (deg): its mount's yaw plus its
// steady drift, or plus one step of its random walk (one draw).
double Actuator::sensorYawDeg() {
  const auto& b = config_.sensor_bias;
  if (!random_walk_bias_) return b.yaw_deg + b.yaw_drift_deg_per_s * sensorTime();
  yaw_walk_deg_ += std::abs(b.yaw_drift_deg_per_s) * 3.0 * std::sqrt(1.0 / config_.sample_rate_hz) * normal_(rng_);
  return b.yaw_deg + yaw_walk_deg_;
}

ActuatorSample Actuator::measure(const std::array<double, 3>& cmd) {
  const SimConfig& c = config_;
  ActuatorSample s;
  s.time_s = time_s_;
  s.command_bar = cmd;
  s.pressure_bar = pressure_;
  const double theta = bend_.norm();
  const double phi = theta > 1e-12 ? std::atan2(bend_.y(), bend_.x()) : 0.0;
  s.true_bend_deg = theta / kRadPerDeg;
  s.true_steer_deg = phi / kRadPerDeg;
  // Tip frame (Webster & Jones): Rz(phi) Ry(theta) Rz(-phi); the sensor's x axis is the tip normal.
  Eigen::Matrix3d g_r_b = rotZ(phi) * rotY(theta) * rotZ(-phi) * rotY(-kPi / 2.0);
  if (c.sensor_bias.enabled)
    g_r_b = rotZ(sensorYawDeg() * kRadPerDeg) * g_r_b * rotY(c.sensor_bias.tilt_deg * kRadPerDeg);
  if (c.sensor.noise_deg > 0.0) {
    const Eigen::Vector3d w(normal_(rng_), normal_(rng_), normal_(rng_));
    const double sigma = c.sensor.noise_deg * kRadPerDeg;
    g_r_b = Eigen::AngleAxisd(sigma * w.norm(), w.normalized()).toRotationMatrix() * g_r_b;
  }
  s.sensor_rotation = g_r_b.transpose();
  anglesFromRotation(s.sensor_rotation, s.bend_deg, s.steer_deg);
  if (c.sensor_bias.enabled) addBendingOffset(s.bend_deg, s.steer_deg);
  return s;
}

// measure()'s reading without noise, as a bending vector (deg), without
// its matrices and angle round trips. Eqs. (5)-(6) read only the first
// column of G_R_B = Rz(yaw) Rz(phi) Ry(theta) Rz(-phi) Ry(-pi/2) Ry(tilt),
// the sensor's x axis (the tip normal), so that axis is turned through the
// same rotations as a vector; its bend acos(z) points along its (x, y),
// and the bias offsets and drifts add to that vector as they do to
// measure()'s angles. The same to rounding, for two sincos and one acos
// where measure() and its conversion take nine sincos, two atan2, an acos
// and five matrix products (a diagnosis's calibrations read a biased sensor
// this way once sensor_bias is a candidate or kept).
Eigen::Vector2d Actuator::bendingWithoutNoise() {
  const SimConfig& c = config_;
  const double theta = bend_.norm();
  const double cp = theta > 1e-12 ? bend_.x() / theta : 1.0, sp = theta > 1e-12 ? bend_.y() / theta : 0.0;
  const bool bias = c.sensor_bias.enabled;
  const double yaw = bias ? sensorYawDeg() * kRadPerDeg : 0.0;
  Eigen::Vector3d x(tilted_x_axis_[0], 0.0, tilted_x_axis_[1]);                  // Ry(tilt - pi/2) e_x
  x = Eigen::Vector3d(cp * x.x() + sp * x.y(), cp * x.y() - sp * x.x(), x.z());  // Rz(-phi)
  const double ct = std::cos(theta), st = std::sin(theta);
  x = Eigen::Vector3d(ct * x.x() + st * x.z(), x.y(), ct * x.z() - st * x.x());  // Ry(theta)
  x = Eigen::Vector3d(cp * x.x() - sp * x.y(), sp * x.x() + cp * x.y(), x.z());  // Rz(phi)
  const double cy = std::cos(yaw), sy = std::sin(yaw);
  x = Eigen::Vector3d(cy * x.x() - sy * x.y(), sy * x.x() + cy * x.y(), x.z());  // Rz(yaw)
  const double across = std::sqrt(x.x() * x.x() + x.y() * x.y());                // a unit vector: no overflow to guard
  Eigen::Vector2d bending = Eigen::Vector2d::Zero();
  if (across > 0.0)
    bending = std::acos(std::clamp(x.z(), -1.0, 1.0)) / kRadPerDeg / across * Eigen::Vector2d(x.x(), x.y());
  return bending + sensorOffset();
}

Eigen::Vector2d Actuator::sensorOffset() const {
  const auto& b = config_.sensor_bias;
  if (!b.enabled) return Eigen::Vector2d::Zero();
  return {b.offset_x_deg + b.drift_x_deg_per_s * sensorTime(), b.offset_y_deg + b.drift_y_deg_per_s * sensorTime()};
}

void Actuator::addBendingOffset(double& bend_deg, double& steer_deg) const {
  const Eigen::Vector2d offset = sensorOffset();
  const double x = bend_deg * std::cos(steer_deg * kRadPerDeg) + offset.x();
  const double y = bend_deg * std::sin(steer_deg * kRadPerDeg) + offset.y();
  if (x == 0.0 && y == 0.0 && bend_deg == 0.0) return;
  bend_deg = std::hypot(x, y);
  steer_deg = std::atan2(y, x) / kRadPerDeg;
}

std::array<double, 3> Actuator::advance(const std::array<double, 3>& command_bar) {
  std::array<double, 3> cmd{};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!std::isfinite(command_bar[i]))
      throw std::invalid_argument("Actuator::step: command for chamber " + std::to_string(i + 1) +
                                  " is not a finite number");
    cmd[i] = std::clamp(command_bar[i], 0.0, config_.max_pressure_bar);
  }
  for (int k = 0; k < substeps_; ++k) substep(cmd);
  ++sample_count_;
  time_s_ = static_cast<double>(sample_count_) / config_.sample_rate_hz;
  return cmd;
}

ActuatorSample Actuator::step(const std::array<double, 3>& command_bar) { return measure(advance(command_bar)); }

BendingReading Actuator::stepReading(const std::array<double, 3>& command_bar, ReadingBranch branch) {
  const std::array<double, 3> cmd = advance(command_bar);
  BendingReading r;
  r.pressure_bar = pressure_;
  if (branch == ReadingBranch::kUnfolded) {
    r.bending_deg = unfoldedReading();
    return r;
  }
  if (config_.sensor.noise_deg == 0.0 && !config_.sensor_bias.enabled && bend_.norm() < 0.5 * kPi) {
    r.bending_deg = bend_ / kRadPerDeg;
    return r;
  }
  if (config_.sensor.noise_deg == 0.0) {
    r.bending_deg = bendingWithoutNoise();
    return r;
  }
  const ActuatorSample s = measure(cmd);
  const double steer = s.steer_deg * kPi / 180.0;  // as diagnose::bendingVector rounds it
  r.bending_deg = s.bend_deg * Eigen::Vector2d(std::cos(steer), std::sin(steer));
  return r;
}

// ReadingBranch::kUnfolded: the segment's bending vector turned by the
// mount's yaw, plus the offsets and their drifts, plus the sensor's noise on
// each axis. The mount's tilt is left out: a tilted axis passes beside the
// pole at 180 deg of bend, where no unfolding is continuous, and at small
// bends it adds about a constant, which an affine map absorbs.
Eigen::Vector2d Actuator::unfoldedReading() {
  Eigen::Vector2d v = bend_ / kRadPerDeg;
  if (config_.sensor_bias.enabled) v = Eigen::Rotation2Dd(sensorYawDeg() * kRadPerDeg) * v + sensorOffset();
  if (config_.sensor.noise_deg > 0.0) v += config_.sensor.noise_deg * Eigen::Vector2d(normal_(rng_), normal_(rng_));
  return v;
}

}  // namespace plsa::sim
