// Simulated three-chamber pneumatic soft segment: valve/chamber pneumatics,
// pressure -> chamber strain, constant-curvature kinematics (Webster & Jones
// 2010), second-order bending dynamics, and a tip orientation sensor read out
// with the paper's eqs. (5)-(6). Effects are switched by SimConfig.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "plsa/sim/sim_config.hpp"

namespace plsa::sim {

/// One measurement, taken at the end of a sample period.
struct ActuatorSample {
  double time_s = 0.0;
  std::array<double, 3> command_bar{};   ///< as applied (after clamping)
  std::array<double, 3> pressure_bar{};  ///< chamber pressures
  double bend_deg = 0.0;                 ///< deflection, eq. (5), from the sensor
  double steer_deg = 0.0;                ///< steering, eq. (6), from the sensor
  double true_bend_deg = 0.0;            ///< noise- and bias-free, for tests
  double true_steer_deg = 0.0;
  Eigen::Matrix3d sensor_rotation = Eigen::Matrix3d::Identity();  ///< B_A_G
};

/// What a calibration compares of one measurement: the sensor's bending
/// vector (bend cos steer, bend sin steer, deg) and the chamber pressures.
struct BendingReading {
  Eigen::Vector2d bending_deg = Eigen::Vector2d::Zero();
  std::array<double, 3> pressure_bar{};
};

/// Which bending vector a reading gives. The sensor's eqs. (5)-(6) fold at
/// 180 deg of bend (190 deg reads as 170 deg the other way), as a real tip
/// sensor's angles do; outputs that are an image of the segment's shape (a
/// tip position) do not fold.
enum class ReadingBranch {
  kSensor,  ///< the sensor's reading, folded into [0, 180] deg of bend
  /// The segment's bending vector turned by the sensor's yaw, plus its
  /// offsets, drifts and noise (white, on each axis); without the mount's
  /// tilt, which has no continuous unfolding near 180 deg.
  kUnfolded,
};

/// Deflection and steering (deg) from a sensor rotation B_A_G, paper eqs. (5), (6).
void anglesFromRotation(const Eigen::Matrix3d& b_a_g, double& bend_deg, double& steer_deg);

/// Configuration subspace (1..3) a steering angle falls in, bounded by the
/// single-chamber bending directions, and the angle measured from its start.
struct Subspace {
  int index;
  double angle_deg;
};
Subspace configurationSubspace(const SimConfig::Geometry& g, double steer_deg);

/// Tip position (m) for arc length, bending and steering (Webster & Jones 2010).
Eigen::Vector3d tipPosition(double arc_length_m, double bend_rad, double steer_rad);

class Actuator {
 public:
  /// Validates the configuration (throws std::invalid_argument).
  Actuator(const SimConfig& config, std::uint64_t seed);

  /// Holds `command_bar` for one sample period and returns the measurement.
  /// Commands are clamped to [0, max_pressure_bar]; a non-finite command throws.
  ActuatorSample step(const std::array<double, 3>& command_bar);
  /// step() read as a bending vector. With an exact sensor (no noise, no
  /// sensor_bias) and a bend under 90 deg that is the bending state itself,
  /// without step()'s rotation round trip (eqs. (5)-(6) give back the bend
  /// and steering the state holds, to rounding); without noise, step()'s
  /// reading through vectors, not its matrices and angles (the same to
  /// rounding); with noise, step()'s measurement, converted (the same
  /// random draws). kUnfolded: see ReadingBranch (its noise draws differ).
  BendingReading stepReading(const std::array<double, 3>& command_bar, ReadingBranch branch = ReadingBranch::kSensor);
  /// Vent: command zero in every chamber.
  ActuatorSample vent() { return step({0.0, 0.0, 0.0}); }
  /// The recording starts here: the sensor's drifts (sensor_bias: the yaw's
  /// drift or random walk, the offsets' drifts) count from this sample, as a
  /// tip sensor zeroed when the logger starts. Without it they count from
  /// construction, so an unrecorded pre-roll of unknown length would leave
  /// its drift in the first recorded sample.
  void startRecording() {
    sensor_epoch_s_ = time_s_;
    yaw_walk_deg_ = 0.0;
  }

  const SimConfig& config() const { return config_; }
  double time() const { return time_s_; }
  int substepsPerSample() const { return substeps_; }

 private:
  /// step() up to its measurement: the clamped command, held for a sample period.
  std::array<double, 3> advance(const std::array<double, 3>& command_bar);
  void substep(const std::array<double, 3>& cmd);
  // substep's stages, in order.
  std::array<double, 3> delayedCommand(const std::array<double, 3>& cmd);
  std::array<double, 3> fillChambers(const std::array<double, 3>& delayed);  ///< effective pressures
  double powerLawRate(double drive, bool filling, double p) const;           ///< pneumatic_lag's "power" law, bar/s
  double hysteresisStrain(std::size_t chamber, double strain);
  double smoothElement(double& z, double& last_strain, double strain) const;
  double creepStrain(std::size_t chamber, double strain);
  void bendToward(Eigen::Vector2d target, double sum_p);
  /// The bending mode's exact step toward `target` (reached from the last step's at a constant rate) at `omega`.
  void bendExactly(const Eigen::Vector2d& target, double omega);
  /// The exponential integrator's change of a chamber's pressure over one
  /// internal step, `gap` below its source, at `rate` (bar/s, before the flow limit).
  double chamberChange(double gap, double rate, bool filling) const;
  int bendingPieces(double omega, double spring_slope) const;
  static constexpr int kMaxBendingPieces = 100000;  ///< a bound on the work of one substep
  /// A chamber's pressure past the deadzone (the smooth law out of line).
  double effectivePressure(double p) const {
    if (!config_.deadzone.enabled) return p;
    return smooth_deadzone_ ? smoothEffectivePressure(p) : std::max(0.0, p - config_.deadzone.threshold_bar);
  }
  double smoothEffectivePressure(double p) const;
  ActuatorSample measure(const std::array<double, 3>& cmd);
  double sensorYawDeg();  ///< sensor_bias's yaw at this sample (a random walk draws once)
  /// measure()'s reading for a sensor without noise as a bending vector
  /// (deg), through vectors rather than measure()'s rotation matrices.
  Eigen::Vector2d bendingWithoutNoise();
  Eigen::Vector2d sensorOffset() const;  ///< sensor_bias's offsets and their drifts now (deg; 0 when off)
  void addBendingOffset(double& bend_deg, double& steer_deg) const;  ///< sensorOffset() added to the angles
  Eigen::Vector2d unfoldedReading();  ///< ReadingBranch::kUnfolded (a random walk's yaw draws once)
  double sensorTime() const { return time_s_ - sensor_epoch_s_; }  ///< seconds the sensor has drifted

  SimConfig config_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  int substeps_ = 1;
  double dt_ = 0.001;
  double time_s_ = 0.0;
  double sensor_epoch_s_ = 0.0;  ///< startRecording()'s time: the sensor's drifts count from it
  std::int64_t sample_count_ = 0;
  std::array<double, 3> pressure_{};
  std::array<double, 3> line_pressure_{};  ///< the supply lines' (power flow law with a line volume)
  double line_blend_ = 0.0;                ///< a line's exact first-order step per substep; 0: no line
  /// log(0.1 bar / the fill or vent time constant): the power flow law's gains, taken once.
  double power_log_gain_fill_ = 0.0, power_log_gain_vent_ = 0.0;
  /// Per chamber: play operator states (weighted_pi: three plays, then the smooth element's z and last strain).
  std::array<std::vector<double>, 3> play_{};
  std::array<double, 3> creep_{};
  std::array<double, 3> creep_slow_{};  ///< second state of two-rate creep
  double yaw_walk_deg_ = 0.0;           ///< random-walk sensor yaw
  // Formulations, decoded once.
  enum class FlowLaw { kLinear, kOrifice, kChoked, kPower };
  enum class StiffeningLaw { kLinear, kQuadratic, kExponential, kPower };
  FlowLaw flow_law_ = FlowLaw::kLinear;
  StiffeningLaw stiffening_law_ = StiffeningLaw::kLinear;
  bool saturating_coupling_ = false, two_rate_creep_ = false, random_walk_bias_ = false, smooth_deadzone_ = false;
  /// Each chamber's bending direction (cos, sin), computed once (not three
  /// sincos per internal step).
  std::array<std::array<double, 2>, 3> bend_direction_{};
  double lever_ = 0.0;        ///< bending per unit strain: 2 length / (3 chamber radius), computed once
  double omega_ = 0.0;        ///< the bending mode's natural frequency (rad/s), unstiffened
  double piece_limit_ = 0.0;  ///< bendingPieces' largest stable w dt: the root of a^2 + 4 zeta a = 2
  // The "exponential" integrator's exact steps, taken once: the share of
  // a first-order part's distance to its source covered in a step (the
  // linear flow law's fill and vent, creep's one or two rates) and the
  // unstiffened bending mode's transition (position and rate, each from
  // the distance to the target and from the rate).
  bool exponential_ = false;
  bool linear_flow_ = true;  ///< a chamber's rate is its drive over a time constant
  double reach_fill_ = 0.0, reach_vent_ = 0.0, reach_creep_ = 0.0, reach_creep_fast_ = 0.0, reach_creep_slow_ = 0.0;
  std::array<double, 4> bend_transition_{};
  Eigen::Vector2d last_target_ = Eigen::Vector2d::Zero();  ///< the bending's target at the last step's end
  /// The sensor's x axis tilted by sensor_bias (x and z of Ry(tilt - pi/2) e_x), computed once.
  std::array<double, 2> tilted_x_axis_{};
  bool weighted_pi_ = false;
  double full_strain_ = 0.0;                        ///< |strain| at max_pressure_bar (weighted_pi's fixed bands)
  std::array<double, 4> pi_weights_{};              ///< narrow, mid, wide play, smooth element
  Eigen::Vector2d bend_ = Eigen::Vector2d::Zero();  ///< theta * (cos phi, sin phi), rad
  Eigen::Vector2d bend_rate_ = Eigen::Vector2d::Zero();
  std::vector<std::array<double, 3>> delay_line_;
  std::size_t delay_head_ = 0;
  std::size_t delay_whole_ = 0;  ///< whole internal steps of transport delay
  double delay_frac_ = 0.0;      ///< and the fraction of one more
};

}  // namespace plsa::sim
