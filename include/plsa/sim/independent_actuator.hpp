// A second simulated three-chamber actuator, written apart from Actuator and
// sharing none of its effect laws: the source of "real" data for checks that
// must not test plsa on its own formulations (the diagnosis self-check, the
// identification generalisation benchmark). Every effect has three or more
// laws outside the family the diagnosis calibrates for that effect
// (sharp Bouc-Wen, Preisach and backlash hysteresis; logistic, cubic-onset
// and sticking deadzones; limiting-stretch, tanh and saturating-exponential
// stiffening; pressure-dependent, quantised-valve and resonant-line
// pneumatics; Prony-series and asymmetric creep; sensor scale, warm-up and
// wandering offsets...), plus laws the diagnosis's flexible families
// contain: Duffing stiffening, exponent-1 Bouc-Wen hysteresis and a
// two-volume line (the self-check leaves them out; identification keeps
// them). Its nominal physics has the same parts as Actuator's (first-order
// chambers, a static elongation map, a second-order bending mode, constant
// curvature), each integrated its own way.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace plsa::sim {

struct IndependentPhysics {
  double sample_rate_hz = 80.0;
  double max_pressure_bar = 0.4;
  // --- nominal -----------------------------------------------------------
  double time_constant_s = 0.05;    ///< chamber filling and venting (first order)
  double max_rate_bar_per_s = 8.0;  ///< flow limit
  double strain_per_bar = 0.75;
  double strain_quadratic = -0.6;  ///< per bar^2
  double natural_freq_hz = 0.8;
  double damping_ratio = 0.85;
  double length_m = 0.09, chamber_radius_m = 0.008;
  std::array<double, 3> bend_direction_deg = {0.0, 120.0, 240.0};
  double noise_deg = 0.05;            ///< white noise on each bending-vector component
  double pressure_noise_bar = 0.002;  ///< white noise on each measured pressure
  // --- effects: a law name ("" = off) and one strength each ------------------
  /// deadzone: "logistic" (p * sigmoid), "cubic_onset" (p^3 / (p^2 + t^2)),
  /// "sticking" (opens above t, closes below t/2); strength: t (bar).
  std::string deadzone;
  double deadzone_bar = 0.06;
  /// hysteresis: "bouc_wen" (exponent 1, on each chamber's strain),
  /// "bouc_wen_sharp" (exponent 2: a sharper knee), "preisach" (a
  /// triangle of relays), "backlash" (mechanical play of the bending
  /// vector); strength: fraction of the strain (bouc_wen, bouc_wen_sharp,
  /// preisach) or degrees / 10 (backlash: 0.1 = 1 deg).
  std::string hysteresis;
  double hysteresis_strength = 0.12;
  /// stiffening: "duffing" (a cubic spring in the bending angle),
  /// "tanh_strain" (strain saturating), "saturating_exp" (stiffness grows
  /// as 1 - exp(-sum p / 0.15 bar)), "limiting_stretch" (Gent-like: the
  /// stiffness 1 / (1 - strength (theta / 40 deg)^2), capped at 10x, grows
  /// without bound toward a limiting bend); strength: dimensionless.
  std::string stiffening;
  double stiffening_strength = 1.0;
  /// coupling: "exponential" (strain x exp(-k others)), "quadratic" (x (1 -
  /// k others^2 / 0.2 bar)), "crosstalk" (a chamber's strain adds to its
  /// neighbours'); strength k (1/bar, or a fraction for crosstalk).
  std::string coupling;
  double coupling_strength = 0.8;
  /// pneumatic lag: "two_volume" (a supply line filling the chamber),
  /// "pressure_dependent" (time constant growing with the pressure),
  /// "quantised_valve" (commands held at 25 Hz and rounded to 0.02 bar),
  /// "resonant_line" (the gas column of a long line: the line's pressure a
  /// damped oscillator, damping ratio 0.35, filling the chamber); strength:
  /// the line's time constant (s), the growth per 0.2 bar, unused, the
  /// line's period (s).
  std::string pneumatic_lag;
  double pneumatic_strength = 0.08;
  /// creep: "prony" (four Kelvin elements, 0.5 to 500 s, equal shares: a
  /// logarithmic creep), "power_law" (six elements, 0.2 to 200 s, shares
  /// rising with the time constant), "asymmetric" (loads at tau, recovers at
  /// 4 tau); strength: the total extra strain fraction; creep_time_s: tau.
  std::string creep;
  double creep_fraction = 0.1;
  double creep_time_s = 6.0;
  /// sensor bias: "scale_offset" (one sensor axis's gain 1.06, a 3 deg
  /// alignment error and a constant offset of the bending vector),
  /// "warm_up" (an offset settling in with time constant 20 s), "wandering"
  /// (a random-walk offset); strength: the offset (deg).
  std::string sensor_bias;
  double sensor_offset_deg = 1.5;
  /// The offset's direction in the bending plane (deg), a property of the
  /// sensor's mounting, so every run recorded with these physics shares it.
  /// NaN: drawn from each recording's seed (a sensor re-mounted per run).
  double sensor_offset_direction_deg = std::numeric_limits<double>::quiet_NaN();

  /// Throws std::invalid_argument naming an unknown law or a value out of range.
  void validate() const;
};

/// The laws IndependentPhysics offers for an effect named as in
/// sim::effectNames() (deadzone, hysteresis, ...); throws for other names.
const std::vector<std::string>& independentLawsOf(const std::string& effect);

/// The range of strengths (setIndependentEffect's) over which `law` of
/// `effect` shows clearly without swamping the nominal response: what the
/// diagnosis self-check and the generalisation benchmark draw from.
std::pair<double, double> independentStrengthRange(const std::string& effect, const std::string& law);

/// Draws the nominal physics widely around the defaults (natural frequency
/// x0.5-1.5, damping ratio 0.3-2.0, strain gain x0.6-1.4, chamber time
/// constant x0.5-3), the draws in this order from `rng`; returns them named
/// "nominal.<name>".
std::vector<std::pair<std::string, double>> drawNominal(IndependentPhysics& physics, std::mt19937_64& rng);

/// The largest bend (deg) the actuator reaches over a command trajectory
/// (rows: samples; columns: the three chambers' commands, bar) from rest,
/// without sensor or pressure noise.
double largestBendDeg(IndependentPhysics physics, const Eigen::MatrixXd& commands);

/// Rescales the segment's lever (its chamber radius: a thinner segment bends
/// more at the same strain) so that the largest bend over `commands` comes
/// within 2% of `target_deg`, in a few passes since stiffening laws bend less
/// than in proportion; returns the largest bend reached. Throws on a target
/// that is not positive and finite or a trajectory that does not bend.
double scaleToBendRange(IndependentPhysics& physics, const Eigen::MatrixXd& commands, double target_deg);

/// Sets the law of `effect` (a name from sim::effectNames()) and its strength.
void setIndependentEffect(IndependentPhysics& physics, const std::string& effect, const std::string& law,
                          double strength);

struct IndependentSample {
  std::array<double, 3> pressure_bar{};
  Eigen::Vector2d bending_deg = Eigen::Vector2d::Zero();  ///< measured bending vector (bend cos steer, bend sin steer)
  /// The same reading without the sensor's white noise (its gain, offsets
  /// and backlash still in it): the best any model of the commands could
  /// predict, short of the sensor's random-walk offset.
  Eigen::Vector2d bending_noise_free_deg = Eigen::Vector2d::Zero();
};

/// Starts vented and at rest; step() advances one sample.
class IndependentActuator {
 public:
  IndependentActuator(const IndependentPhysics& physics, std::uint64_t seed);
  IndependentSample step(const std::array<double, 3>& command_bar);

 private:
  void substep(const std::array<double, 3>& cmd, double dt);
  // substep's stages, in order.
  std::array<double, 3> valveDrive(const std::array<double, 3>& cmd);
  std::array<double, 3> fillChambers(const std::array<double, 3>& drive, double dt);  ///< effective pressures
  std::array<double, 3> chamberStrains(const std::array<double, 3>& p_eff, double sum_p) const;
  void bendToward(const Eigen::Vector2d& target, double sum_p, double dt);
  double effectivePressure(std::size_t i, double p);
  double hysteretic(std::size_t i, double strain, double dt);
  double creepOf(std::size_t i, double strain, double dt);
  Eigen::Vector2d measuredNoiseFree(const Eigen::Vector2d& bend);  ///< the sensor's reading before its white noise

  IndependentPhysics ph_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  int substeps_ = 1;
  double t_ = 0.0;
  std::array<double, 3> p_{}, line_{}, line_rate_{}, held_cmd_{};
  double next_valve_update_ = 0.0;
  std::array<bool, 3> open_{};
  std::array<double, 3> bw_z_{}, last_strain_{};
  std::array<std::array<bool, 55>, 3> relays_{};
  std::array<std::array<double, 6>, 3> creep_{};
  Eigen::Vector2d bend_ = Eigen::Vector2d::Zero(), rate_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d backlash_out_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d wander_ = Eigen::Vector2d::Zero();
};

}  // namespace plsa::sim
