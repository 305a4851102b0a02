#include "plsa/sim/independent_actuator.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>

#include "plsa/core/angle_units.hpp"
#include "plsa/core/check.hpp"

namespace plsa::sim {
namespace {

constexpr double kSubstep_s = 0.0005;
constexpr int kPreisachLevels = 10;  // 55 relays per chamber

const std::map<std::string, std::vector<std::string>>& laws() {
  static const std::map<std::string, std::vector<std::string>> l = {
      {"deadzone", {"logistic", "cubic_onset", "sticking"}},
      {"hysteresis", {"bouc_wen", "bouc_wen_sharp", "preisach", "backlash"}},
      {"stiffening", {"duffing", "tanh_strain", "saturating_exp", "limiting_stretch"}},
      {"coupling", {"exponential", "quadratic", "crosstalk"}},
      {"pneumatic_lag", {"two_volume", "resonant_line", "pressure_dependent", "quantised_valve"}},
      {"creep", {"prony", "power_law", "asymmetric"}},
      {"sensor_bias", {"scale_offset", "warm_up", "wandering"}}};
  return l;
}

std::string* lawSlot(IndependentPhysics& p, const std::string& effect) {
  if (effect == "deadzone") return &p.deadzone;
  if (effect == "hysteresis") return &p.hysteresis;
  if (effect == "stiffening") return &p.stiffening;
  if (effect == "coupling") return &p.coupling;
  if (effect == "pneumatic_lag") return &p.pneumatic_lag;
  if (effect == "creep") return &p.creep;
  if (effect == "sensor_bias") return &p.sensor_bias;
  throw std::invalid_argument("independent physics: unknown effect '" + effect + "'");
}

double* strengthSlot(IndependentPhysics& p, const std::string& effect) {
  if (effect == "deadzone") return &p.deadzone_bar;
  if (effect == "hysteresis") return &p.hysteresis_strength;
  if (effect == "stiffening") return &p.stiffening_strength;
  if (effect == "coupling") return &p.coupling_strength;
  if (effect == "pneumatic_lag") return &p.pneumatic_strength;
  if (effect == "creep") return &p.creep_fraction;
  if (effect == "sensor_bias") return &p.sensor_offset_deg;
  throw std::invalid_argument("independent physics: unknown effect '" + effect + "'");
}

void requireIn(double v, double lo, double hi, const char* name) {
  if (!std::isfinite(v) || v < lo || v > hi)
    throw std::invalid_argument(std::string("independent physics: ") + name + " = " + std::to_string(v) +
                                " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

}  // namespace

const std::vector<std::string>& independentLawsOf(const std::string& effect) {
  const auto it = laws().find(effect);
  if (it == laws().end()) throw std::invalid_argument("independent physics: unknown effect '" + effect + "'");
  return it->second;
}

std::pair<double, double> independentStrengthRange(const std::string& effect, const std::string& law) {
  static const std::map<std::string, std::pair<double, double>> r = {{"deadzone", {0.04, 0.10}},
                                                                     {"hysteresis.bouc_wen", {0.25, 0.5}},
                                                                     {"hysteresis.bouc_wen_sharp", {0.25, 0.5}},
                                                                     {"hysteresis.preisach", {0.25, 0.5}},
                                                                     {"hysteresis.backlash", {0.05, 0.15}},
                                                                     {"stiffening.duffing", {0.4, 1.2}},
                                                                     {"stiffening.tanh_strain", {0.7, 1.3}},
                                                                     {"stiffening.saturating_exp", {2.0, 5.0}},
                                                                     {"stiffening.limiting_stretch", {0.4, 0.8}},
                                                                     {"coupling.exponential", {1.0, 2.5}},
                                                                     {"coupling.quadratic", {0.1, 0.3}},
                                                                     {"coupling.crosstalk", {0.15, 0.35}},
                                                                     {"pneumatic_lag.two_volume", {0.06, 0.15}},
                                                                     {"pneumatic_lag.pressure_dependent", {1.0, 3.0}},
                                                                     {"pneumatic_lag.quantised_valve", {0.0, 0.0}},
                                                                     {"pneumatic_lag.resonant_line", {0.1, 0.25}},
                                                                     {"creep", {0.06, 0.15}},
                                                                     {"sensor_bias", {1.0, 3.0}}};
  const auto it = r.find(effect + "." + law);
  return it != r.end() ? it->second : r.at(effect);
}

std::vector<std::pair<std::string, double>> drawNominal(IndependentPhysics& t, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * uni(rng); };
  t.natural_freq_hz *= between(0.5, 1.5);
  t.damping_ratio = between(0.3, 2.0);
  const double gain = between(0.6, 1.4);
  t.strain_per_bar *= gain;
  t.strain_quadratic *= gain;
  t.time_constant_s *= between(0.5, 3.0);
  return {{"nominal.natural_freq_hz", t.natural_freq_hz},
          {"nominal.damping_ratio", t.damping_ratio},
          {"nominal.gain", gain},
          {"nominal.time_constant_s", t.time_constant_s}};
}

void setIndependentEffect(IndependentPhysics& physics, const std::string& effect, const std::string& law,
                          double strength) {
  const auto& known = independentLawsOf(effect);
  if (!law.empty() && std::find(known.begin(), known.end(), law) == known.end())
    throw std::invalid_argument("independent physics: " + effect + " has no law '" + law + "'");
  *lawSlot(physics, effect) = law;
  *strengthSlot(physics, effect) = strength;
}

void IndependentPhysics::validate() const {
  requireIn(sample_rate_hz, 1.0, 10000.0, "sample_rate_hz");
  requireIn(max_pressure_bar, 0.01, 1.0, "max_pressure_bar");
  requireIn(time_constant_s, 0.002, 2.0, "time_constant_s");
  requireIn(max_rate_bar_per_s, 0.05, 100.0, "max_rate_bar_per_s");
  requireIn(strain_per_bar, 0.01, 5.0, "strain_per_bar");
  requireIn(natural_freq_hz, 0.05, 20.0, "natural_freq_hz");
  requireIn(damping_ratio, 0.05, 5.0, "damping_ratio");
  requireIn(noise_deg, 0.0, 10.0, "noise_deg");
  requireIn(pressure_noise_bar, 0.0, 1.0, "pressure_noise_bar");
  if (strain_per_bar + 2.0 * strain_quadratic * max_pressure_bar <= 0.0)
    throw std::invalid_argument("independent physics: the elongation stops rising below max_pressure_bar");
  IndependentPhysics copy = *this;
  for (const auto& [effect, known] : laws()) {
    const std::string& law = *lawSlot(copy, effect);
    if (!law.empty() && std::find(known.begin(), known.end(), law) == known.end())
      throw std::invalid_argument("independent physics: " + effect + " has no law '" + law + "'");
  }
  requireIn(deadzone_bar, 0.0, 0.2, "deadzone_bar");
  requireIn(hysteresis_strength, 0.0, 0.9, "hysteresis_strength");
  requireIn(stiffening_strength, 0.0, 10.0, "stiffening_strength");
  requireIn(coupling_strength, 0.0, 3.0, "coupling_strength");
  requireIn(pneumatic_strength, 0.0, 5.0, "pneumatic_strength");
  requireIn(creep_fraction, 0.0, 0.5, "creep_fraction");
  requireIn(creep_time_s, 0.1, 200.0, "creep_time_s");
  requireIn(sensor_offset_deg, 0.0, 20.0, "sensor_offset_deg");
  if (!std::isnan(sensor_offset_direction_deg))
    requireIn(sensor_offset_direction_deg, -360.0, 360.0, "sensor_offset_direction_deg");
}

IndependentActuator::IndependentActuator(const IndependentPhysics& physics, std::uint64_t seed)
    : ph_(physics), rng_(seed) {
  ph_.validate();
  substeps_ = std::max(1, static_cast<int>(std::lround(1.0 / (ph_.sample_rate_hz * kSubstep_s))));
  // The sensor errors' fixed parts: a direction for the offset, a sign for the gain.
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double drawn = 2.0 * kPi * uni(rng_);  // drawn either way: the noise that follows is the same
  const double a = std::isnan(ph_.sensor_offset_direction_deg) ? drawn : ph_.sensor_offset_direction_deg * kPi / 180.0;
  wander_ = Eigen::Vector2d(std::cos(a), std::sin(a));  // the offset's direction until the walk starts
}

double IndependentActuator::effectivePressure(std::size_t i, double p) {
  const double t = ph_.deadzone_bar;
  if (ph_.deadzone == "logistic") return t > 0 ? p * sigmoid((p - t) / (0.25 * t)) : p;
  if (ph_.deadzone == "cubic_onset") return p * p * p / (p * p + t * t + 1e-12);
  if (ph_.deadzone == "sticking") {
    if (p > t) open_[i] = true;
    if (p < 0.5 * t) open_[i] = false;
    return open_[i] ? std::max(0.0, p - 0.5 * t) : 0.0;
  }
  return p;
}

double IndependentActuator::hysteretic(std::size_t i, double s, double dt) {
  (void)dt;
  const double h = ph_.hysteresis_strength;
  const double top =
      ph_.strain_per_bar * ph_.max_pressure_bar + ph_.strain_quadratic * ph_.max_pressure_bar * ph_.max_pressure_bar;
  if (ph_.hysteresis == "bouc_wen") {
    // z' = s' - (beta |s'| z + gamma s' |z|), bounded by `top`: steeper on unloading.
    const double ds = s - last_strain_[i];
    const double beta = 0.75 / top, gamma = 0.25 / top;
    bw_z_[i] += ds - (beta * std::abs(ds) * bw_z_[i] + gamma * ds * std::abs(bw_z_[i]));
    last_strain_[i] = s;
    return (1.0 - h) * s + h * bw_z_[i];
  }
  if (ph_.hysteresis == "bouc_wen_sharp") {
    // Exponent 2: z' = s' - (beta |s'| z |z| + gamma s' z^2), a sharper knee toward the same bound.
    const double ds = s - last_strain_[i];
    const double beta = 0.75 / (top * top), gamma = 0.25 / (top * top);
    double& z = bw_z_[i];
    z += ds - (beta * std::abs(ds) * z * std::abs(z) + gamma * ds * z * z);
    z = std::clamp(z, -top, top);
    last_strain_[i] = s;
    return (1.0 - h) * s + h * z;
  }
  if (ph_.hysteresis == "preisach") {
    int on = 0, k = 0;
    for (int a = 0; a < kPreisachLevels; ++a)
      for (int b = 0; b <= a; ++b, ++k) {
        const double up = top * (a + 1) / (kPreisachLevels + 1), down = top * b / (kPreisachLevels + 1);
        bool& r = relays_[i][static_cast<std::size_t>(k)];
        if (s >= up) r = true;
        if (s <= down) r = false;
        on += r;
      }
    const double fraction = static_cast<double>(on) / static_cast<double>(k);
    return (1.0 - h) * s + h * top * fraction;
  }
  return s;
}

double IndependentActuator::creepOf(std::size_t i, double s, double dt) {
  auto& c = creep_[i];
  const double f = ph_.creep_fraction, tau = ph_.creep_time_s;
  if (ph_.creep == "prony") {
    static const double scale[4] = {0.1, 1.0, 10.0, 100.0};
    double sum = 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      c[k] += (0.25 * f * s - c[k]) * (1.0 - std::exp(-dt / (scale[k] * tau)));
      sum += c[k];
    }
    return sum;
  }
  if (ph_.creep == "power_law") {
    double weights[6], total = 0.0, sum = 0.0;
    for (int k = 0; k < 6; ++k) total += weights[k] = std::pow(std::pow(10.0, (k - 2.5) * 0.6), 0.3);
    for (std::size_t k = 0; k < 6; ++k) {
      const double tk = tau * std::pow(10.0, (static_cast<double>(k) - 2.5) * 0.6);
      c[k] += (weights[k] / total * f * s - c[k]) * (1.0 - std::exp(-dt / tk));
      sum += c[k];
    }
    return sum;
  }
  if (ph_.creep == "asymmetric") {
    const double target = f * s;
    c[0] += (target - c[0]) * (1.0 - std::exp(-dt / (target > c[0] ? tau : 4.0 * tau)));
    return c[0];
  }
  return 0.0;
}

// The command the chambers see: a quantised valve holds a 0.02 bar step for 40 ms.
std::array<double, 3> IndependentActuator::valveDrive(const std::array<double, 3>& cmd) {
  if (ph_.pneumatic_lag != "quantised_valve") return cmd;
  if (t_ >= next_valve_update_) {
    for (std::size_t i = 0; i < 3; ++i) held_cmd_[i] = 0.02 * std::round(cmd[i] / 0.02);
    next_valve_update_ += 1.0 / 25.0;
  }
  return held_cmd_;
}

// Each chamber's pressure one exact first-order step toward its drive,
// flow-limited; returns the pressures past the deadzone.
std::array<double, 3> IndependentActuator::fillChambers(const std::array<double, 3>& drive, double dt) {
  const IndependentPhysics& ph = ph_;
  std::array<double, 3> p_eff{};
  for (std::size_t i = 0; i < 3; ++i) {
    double source = drive[i];
    if (ph.pneumatic_lag == "two_volume") {
      line_[i] += (drive[i] - line_[i]) * (1.0 - std::exp(-dt / std::max(1e-3, ph.pneumatic_strength)));
      source = line_[i];
    }
    if (ph.pneumatic_lag == "resonant_line") {
      // The gas column's inertia: the line's pressure a damped oscillator
      // (damping ratio 0.35) of period `pneumatic_strength`, semi-implicit.
      const double w = 2.0 * kPi / std::max(1e-2, ph.pneumatic_strength);
      line_rate_[i] += (w * w * (drive[i] - line_[i]) - 2.0 * 0.35 * w * line_rate_[i]) * dt;
      line_[i] += line_rate_[i] * dt;
      source = std::max(0.0, line_[i]);
    }
    double tau = ph.time_constant_s;
    if (ph.pneumatic_lag == "pressure_dependent") tau *= 1.0 + ph.pneumatic_strength * p_[i] / 0.2;
    const double step = (source - p_[i]) * (1.0 - std::exp(-dt / tau));
    p_[i] += std::clamp(step, -ph.max_rate_bar_per_s * dt, ph.max_rate_bar_per_s * dt);
    p_eff[i] = effectivePressure(i, p_[i]);
  }
  return p_eff;
}

// Each chamber's strain from its pressure, with the neighbours' coupling and
// a saturating strain.
std::array<double, 3> IndependentActuator::chamberStrains(const std::array<double, 3>& p_eff, double sum_p) const {
  const IndependentPhysics& ph = ph_;
  std::array<double, 3> strain{};
  for (std::size_t i = 0; i < 3; ++i) {
    double s = ph.strain_per_bar * p_eff[i] + ph.strain_quadratic * p_eff[i] * p_eff[i];
    const double others = sum_p - p_eff[i];
    if (ph.coupling == "exponential") s *= std::exp(-ph.coupling_strength * others);
    if (ph.coupling == "quadratic") s *= std::max(0.0, 1.0 - ph.coupling_strength * others * others / 0.2);
    if (ph.stiffening == "tanh_strain") {
      const double top = ph.strain_per_bar * ph.max_pressure_bar;
      const double s0 = top / std::max(0.05, ph.stiffening_strength);
      s = s0 * std::tanh(s / s0);
    }
    strain[i] = s;
  }
  if (ph.coupling == "crosstalk") {
    const std::array<double, 3> own = strain;
    for (std::size_t i = 0; i < 3; ++i)
      strain[i] = own[i] + ph.coupling_strength * 0.5 * (own[(i + 1) % 3] + own[(i + 2) % 3]);
  }
  return strain;
}

// The bending mode one velocity-Verlet step toward `target`, stiffened by
// the summed pressure or by the bend itself.
void IndependentActuator::bendToward(const Eigen::Vector2d& target, double sum_p, double dt) {
  const IndependentPhysics& ph = ph_;
  double omega = 2.0 * kPi * ph.natural_freq_hz;
  if (ph.stiffening == "saturating_exp")
    omega *= std::sqrt(1.0 + ph.stiffening_strength * (1.0 - std::exp(-sum_p / 0.15)));
  // theta'' = w^2 (target - spring(theta)) - 2 zeta w theta'.
  auto accel = [&](const Eigen::Vector2d& x, const Eigen::Vector2d& v) {
    Eigen::Vector2d spring = x;
    if (ph.stiffening == "duffing") {
      const double theta0 = 20.0 * kRadPerDeg;
      spring *= 1.0 + ph.stiffening_strength * x.squaredNorm() / (theta0 * theta0);
    }
    if (ph.stiffening == "limiting_stretch") {
      // Gent-like: the stiffness diverges as the bend nears a limiting angle
      // of 40 deg / sqrt(strength) (capped at 10x just short of it).
      const double theta0 = 40.0 * kRadPerDeg;
      spring /= 1.0 - std::min(0.9, ph.stiffening_strength * x.squaredNorm() / (theta0 * theta0));
    }
    return Eigen::Vector2d(omega * omega * (target - spring) - 2.0 * ph.damping_ratio * omega * v);
  };
  const Eigen::Vector2d a0 = accel(bend_, rate_);
  const Eigen::Vector2d half = rate_ + 0.5 * dt * a0;
  bend_ += dt * half;
  rate_ = half + 0.5 * dt * accel(bend_, half);
}

void IndependentActuator::substep(const std::array<double, 3>& cmd, double dt) {
  const std::array<double, 3> p_eff = fillChambers(valveDrive(cmd), dt);
  double sum_p = 0.0;
  for (double p : p_eff) sum_p += p;
  const std::array<double, 3> strain = chamberStrains(p_eff, sum_p);
  Eigen::Vector2d target = Eigen::Vector2d::Zero();
  const double lever = 2.0 * ph_.length_m / (3.0 * ph_.chamber_radius_m);
  for (std::size_t i = 0; i < 3; ++i) {
    double s = hysteretic(i, strain[i], dt);
    s += creepOf(i, s, dt);
    const double dir = ph_.bend_direction_deg[i] * kRadPerDeg;
    target += lever * s * Eigen::Vector2d(std::cos(dir), std::sin(dir));
  }
  bendToward(target, sum_p, dt);
  t_ += dt;
}

Eigen::Vector2d IndependentActuator::measuredNoiseFree(const Eigen::Vector2d& bend_rad) {
  Eigen::Vector2d v = bend_rad / kRadPerDeg;
  if (ph_.hysteresis == "backlash") {
    const double b = 10.0 * ph_.hysteresis_strength;
    const Eigen::Vector2d d = v - backlash_out_;
    if (d.norm() > b) backlash_out_ = v - b * d.normalized();
    v = backlash_out_;
  }
  const double o = ph_.sensor_offset_deg;
  if (ph_.sensor_bias == "scale_offset") {
    // Turned on its mount, one axis's gain off by 6%: no candidate's mount
    // yaw and no actuator gain makes the ellipse.
    const double a = 3.0 * kRadPerDeg;
    v = Eigen::Vector2d(1.06, 1.0).asDiagonal() * (Eigen::Rotation2Dd(a).toRotationMatrix() * v) + o * wander_;
  } else if (ph_.sensor_bias == "warm_up") {
    v += o * (1.0 - std::exp(-t_ / 20.0)) * wander_;
  } else if (ph_.sensor_bias == "wandering") {
    const double sd = 0.15 * o * std::sqrt(1.0 / ph_.sample_rate_hz);
    wander_ += Eigen::Vector2d(normal_(rng_), normal_(rng_)) * sd / std::max(1e-9, o);
    v += o * wander_;
  }
  return v;
}

IndependentSample IndependentActuator::step(const std::array<double, 3>& command_bar) {
  std::array<double, 3> cmd{};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!std::isfinite(command_bar[i]))
      throw std::invalid_argument("IndependentActuator::step: command for chamber " + std::to_string(i + 1) +
                                  " is not a finite number");
    cmd[i] = std::clamp(command_bar[i], 0.0, ph_.max_pressure_bar);
  }
  const double dt = 1.0 / (ph_.sample_rate_hz * substeps_);
  for (int k = 0; k < substeps_; ++k) substep(cmd, dt);
  IndependentSample s;
  for (std::size_t i = 0; i < 3; ++i) s.pressure_bar[i] = p_[i] + ph_.pressure_noise_bar * normal_(rng_);
  s.bending_noise_free_deg = measuredNoiseFree(bend_);
  s.bending_deg = s.bending_noise_free_deg;
  if (ph_.noise_deg > 0) s.bending_deg += ph_.noise_deg * Eigen::Vector2d(normal_(rng_), normal_(rng_));
  return s;
}

double largestBendDeg(IndependentPhysics physics, const Eigen::MatrixXd& commands) {
  PLSA_CHECK(commands.cols() == 3, "largestBendDeg: need one command column per chamber");
  physics.noise_deg = 0.0;
  physics.pressure_noise_bar = 0.0;
  IndependentActuator a(physics, 1);
  double largest = 0.0;
  for (Eigen::Index k = 0; k < commands.rows(); ++k)
    largest = std::max(largest, a.step({commands(k, 0), commands(k, 1), commands(k, 2)}).bending_deg.norm());
  return largest;
}

double scaleToBendRange(IndependentPhysics& physics, const Eigen::MatrixXd& commands, double target_deg) {
  PLSA_CHECK(std::isfinite(target_deg) && target_deg > 0.0, "scaleToBendRange: the target must be positive");
  // Secant steps on log(bend) against log(radius), from the proportional law (slope -1).
  double reached = largestBendDeg(physics, commands), slope = -1.0;
  for (int pass = 0; pass < 12 && std::abs(reached / target_deg - 1.0) > 0.02; ++pass) {
    PLSA_CHECK(reached > 1e-6, "scaleToBendRange: the commands do not bend the segment");
    const double log_r = std::log(physics.chamber_radius_m), log_bend = std::log(reached);
    physics.chamber_radius_m = std::exp(log_r + (std::log(target_deg) - log_bend) / slope);
    const double next = largestBendDeg(physics, commands);
    if (next > 1e-6 && std::abs(std::log(physics.chamber_radius_m) - log_r) > 1e-9)
      slope = std::clamp((std::log(next) - log_bend) / (std::log(physics.chamber_radius_m) - log_r), -2.0, -0.05);
    reached = next;
  }
  return reached;
}

}  // namespace plsa::sim
