// Configuration of the simulated three-chamber actuator: nominal physics plus
// the candidate unmodelled effects, each a named module that can be switched
// on or off and whose parameters are addressable by name (for calibration).
#pragma once

#include <array>
#include <string>
#include <vector>

namespace plsa::sim {

/// The candidate effects, in the order the diagnosis lists them.
inline const std::vector<std::string>& effectNames() {
  static const std::vector<std::string> names = {"deadzone",      "hysteresis", "stiffening", "coupling",
                                                 "pneumatic_lag", "creep",      "sensor_bias"};
  return names;
}

/// A named parameter with its physical bounds (what a calibration may try).
struct ParamRef {
  std::string name;
  double* value;
  double lower;
  double upper;
  std::string unit;
};

/// The sample rates the simulator runs at (SimConfig::sample_rate_hz).
inline constexpr double kMinSampleRateHz = 1.0, kMaxSampleRateHz = 10000.0;

struct SimConfig {
  double sample_rate_hz = 80.0;
  double internal_step_s = 0.001;
  /// How an internal step integrates the linear parts: "euler" (explicit
  /// Euler chambers and creep, semi-implicit Euler bending) or
  /// "exponential": each first-order part's exact step (a nonlinear flow
  /// law's at the rate it has at the step's start) and the bending mode's
  /// exact step toward a target moving at a constant rate from the last
  /// step's to this one's (a hardening spring keeps semi-implicit Euler),
  /// accurate at steps several times longer.
  std::string integrator = "euler";
  double max_pressure_bar = 0.4;  ///< commands are clamped to [0, this]

  struct Geometry {
    double length_m = 0.09;
    double chamber_radius_m = 0.008;  ///< chamber axis to segment axis
    /// Directions (deg) the tip bends to under each chamber alone.
    std::array<double, 3> bend_direction_deg = {0.0, 120.0, 240.0};
  } geometry;

  struct Pneumatics {
    double time_constant_s = 0.05;
    double max_rate_bar_per_s = 8.0;  ///< flow limit
  } pneumatics;

  struct Elongation {
    double strain_per_bar = 0.75;  ///< chamber strain per bar of effective pressure
    double quadratic = -0.6;       ///< static nonlinearity: strain += q p^2 (per bar^2)
  } elongation;

  struct Bending {
    double natural_freq_hz = 0.8;
    double damping_ratio = 0.85;
  } bending;

  struct Sensor {
    double noise_deg = 0.05;  ///< std of a random rotation per sample
  } sensor;

  // --- candidate effects ------------------------------------------------
  struct Deadzone {
    bool enabled = true;
    std::string formulation = "sharp";  ///< "sharp" | "smooth"
    double threshold_bar = 0.06;
    double smooth_width_bar = 0.01;  ///< only for "smooth"
  } deadzone;
  struct Hysteresis {
    bool enabled = true;
    /// "play" | "prandtl_ishlinskii" (five equal plays, widths spread to 2x) |
    /// "weighted_pi": a Prandtl-Ishlinskii operator with fitted weights,
    /// strain + sum_k w_k (play_k - strain) over plays of width/2, width and
    /// 2 width (|weights| scaled to sum to at most 1; the rest is the linear
    /// part). A positive weight adds a loop whose output lags the strain (a
    /// play); a negative one the opposite loop, steeper on unloading (a
    /// stop: elastoplastic). Beside the plays, a smooth element z (Bouc-Wen
    /// of exponent 1 on the strain, dz = ds - beta |ds| z - gamma ds |z|)
    /// adds weight_smooth (z - strain): z saturates at smooth_saturation
    /// times the strain at full pressure; smooth_asymmetry, (beta - gamma) /
    /// (beta + gamma), sets its unloading slope, 1 + asymmetry z / bound:
    /// steeper than its first loading's 1 above 0, shallower below.
    /// It contains "play" (weights 0, 1, 0, smooth 0) and no hysteresis
    /// (all weights 0).
    std::string formulation = "play";
    double width = 0.12;                                              ///< play half-width as a fraction of the strain
    double weight_narrow = 0.0, weight_mid = 1.0, weight_wide = 0.0;  ///< only for "weighted_pi"
    /// Only for "weighted_pi": the share of each band that is fixed, a
    /// fraction of the strain at full pressure, instead of proportional to
    /// the strain. 0: the loop closes at zero; 1: classic plays of fixed
    /// width, which leave a remanent strain when the chamber vents.
    double fixed_band_share = 0.0;
    double weight_smooth = 0.0;      ///< only for "weighted_pi": the smooth element's weight (in the |weights| sum)
    double smooth_saturation = 0.5;  ///< only for "weighted_pi": z's bound, a fraction of the strain at full pressure
    double smooth_asymmetry = 0.0;   ///< only for "weighted_pi": (beta - gamma) / (beta + gamma); not calibrated
  } hysteresis;
  struct Stiffening {
    bool enabled = true;
    /// Stiffness grows by (1 + per_bar * s), s = sum of p_eff, or:
    /// "quadratic": 1 + per_bar s^2 / 0.2 bar;
    /// "exponential": 1 + per_bar 0.2 bar (e^(s/0.2 bar) - 1) / (e - 1), equal to linear at 0 and 0.2 bar;
    /// "power": 1 + per_bar 0.2 bar (s/0.2 bar)^exponent, spanning linear (1) and quadratic (2).
    std::string formulation = "linear";
    double per_bar = 20.0;
    double exponent = 1.5;  ///< only for "power"
    /// Only for "power": how much of the stiffening also holds the static
    /// deflection back (the target divided by growth^static_share). 0: the
    /// stiffer mode reaches the same bend sooner (the other laws); 1: a
    /// stiffer spring under the same drive bends less, as a hardening
    /// material does.
    double static_share = 0.0;
    /// Only for "power": the bending spring also hardens with the bending
    /// angle theta (rad), restoring force theta (1 + per_rad2 theta^2), as a
    /// Duffing spring; 0 is the spring of the other laws.
    double per_rad2 = 0.0;
  } stiffening;
  struct Coupling {
    bool enabled = true;
    std::string formulation = "multiplicative";  ///< "multiplicative" | "saturating" (strain / (1 + per_bar * others))
    /// A pressurised chamber's wall bulges into its neighbours and stiffens
    /// them: each strain is scaled by (1 - per_bar * other chambers' p_eff).
    double per_bar = 0.8;
  } coupling;
  struct PneumaticLag {
    bool enabled = true;
    /// "linear"; "orifice": flow grows with the square root of the pressure
    /// difference (equal to linear at 0.1 bar), as through a restriction;
    /// "choked": flow stops growing beyond 0.05 bar of difference, as at sonic
    /// speed; "power": difference^exponent (equal at 0.1 bar), spanning
    /// orifice (0.5) and linear (1), with time constants that scale by
    /// exp(pressure_per_bar x the chamber's pressure), as a chamber whose
    /// volume or outflow changes with its pressure, and a supply line's
    /// volume ahead of the chamber (line_time_constant_s).
    std::string formulation = "linear";
    double fill_time_constant_s = 0.08;
    double vent_time_constant_s = 0.03;
    double delay_s = 0.03;
    double exponent = 0.75;         ///< only for "power"
    double pressure_per_bar = 0.0;  ///< only for "power"
    /// Only for "power": a supply line's volume between the valve and the
    /// chamber, filled first-order with this time constant ahead of the
    /// chamber's own flow (two volumes in series, as a long tube makes);
    /// 0: none, the chamber fills from the valve.
    double line_time_constant_s = 0.0;
  } pneumatic_lag;
  struct Creep {
    bool enabled = true;
    /// "exponential" | "two_rate": half the creep at time_constant_s / 5, half at 2 time_constant_s.
    std::string formulation = "exponential";
    double fraction = 0.08;  ///< extra strain reached under a constant pressure
    double time_constant_s = 8.0;
  } creep;
  struct SensorBias {
    bool enabled = true;
    /// "linear_drift" | "random_walk": yaw wanders (steps of |yaw drift| sqrt(dt) x 3) instead of drifting steadily.
    std::string formulation = "linear_drift";
    double tilt_deg = 1.5;  ///< mount misalignment
    /// The mount turned about the segment's axis: a constant yaw of the
    /// reading, the drift adding to it; 0 by default.
    double yaw_deg = 0.0;
    double yaw_drift_deg_per_s = 0.02;
    /// A zero error and a linear drift of each bending-vector component
    /// (bend cos steer, bend sin steer), as an uncalibrated or warming
    /// sensor shows; 0 by default.
    double offset_x_deg = 0.0, offset_y_deg = 0.0;
    double drift_x_deg_per_s = 0.0, drift_y_deg_per_s = 0.0;
  } sensor_bias;

  bool effectEnabled(const std::string& effect) const;
  /// The effect's formulation (one of formulationsOf(effect)); throws for unknown effects.
  std::string& formulationOf(const std::string& effect);
  void setEffectEnabled(const std::string& effect, bool on);
  /// The calibratable parameters of an effect, or "nominal" for the base physics.
  std::vector<ParamRef> parameters(const std::string& module);

  /// Throws std::invalid_argument naming the first value out of range.
  void validate() const;
};

/// The formulations an effect can take, its default first.
const std::vector<std::string>& formulationsOf(const std::string& effect);

/// SimConfig::integrator's values, the default first.
const std::vector<std::string>& integratorNames();

/// Throws std::invalid_argument "<field> '<name>' is not one of <names>"
/// unless `name` is one of integratorNames().
void requireIntegratorName(const std::string& name, const std::string& field);

/// The effect's flexible law (one whose shape parameters span its fixed
/// laws: "power" for stiffening and pneumatic_lag, "weighted_pi" for
/// hysteresis), or "" when it has none.
std::string flexibleFormulationOf(const std::string& effect);

/// JSON I/O. Unknown keys and wrong types are errors naming the key path.
SimConfig loadSimConfig(const std::string& path);
SimConfig simConfigFromJson(const std::string& text, const std::string& source = "<json>");
std::string simConfigToJson(const SimConfig& config);

}  // namespace plsa::sim
