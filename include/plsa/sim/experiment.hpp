// Identification and validation experiments (paper Section V-A, Table I):
// single-chamber staircases, the two-chamber reference-pressure grid with one
// input moving at a time, smooth joystick-like validation runs, and a static map.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/io/csv_log.hpp"
#include "plsa/sim/actuator.hpp"

namespace plsa::sim {

struct ExperimentOptions {
  double sample_rate_hz = 80.0;
  double hold_s = 4.0;          ///< time at each level, long enough to settle
  double initial_rest_s = 2.0;  ///< staircase: recorded rest before the first step
  double preroll_s = 5.0;       ///< grid2: ramp to the first point and settle, unrecorded
  // staircase1
  int staircase_steps = 14;
  double staircase_max_bar = 0.35;
  int staircase_chamber = 1;
  // grid2 (paper: 0.20 to 0.35 bar, four levels per chamber)
  std::vector<double> grid_levels_bar = {0.20, 0.25, 0.30, 0.35};
  std::array<int, 2> grid_chambers = {1, 2};
  // static_map: from a base below the grid, step both grid chambers together to
  // each point of an n x n map over the grid's range and hold until settled.
  int static_map_points = 7;
  double static_map_base_bar = 0.19;
  double static_map_base_s = 10.0;  ///< back at the base between points
  double static_map_hold_s = 40.0;  ///< five time constants of the default creep
  // joystick
  double joystick_duration_s = 60.0;
  /// The grid's range and 0.01 bar beyond it at either end: mostly
  /// validation, with the little extrapolation a hand-driven path will do
  /// (the demo's seeds 1 to 8 spend 4 to 13% of their samples outside 0.20
  /// to 0.35 bar on one chamber or both).
  double joystick_min_bar = 0.19;
  double joystick_max_bar = 0.36;
  double joystick_bandwidth_hz = 0.3;
  /// Unrecorded ramp and hold before a joystick run. Free simulation starts
  /// from a steady state, so the run must too: 40 s is five time constants
  /// of the default creep (8 s), leaving under 1% of it.
  double joystick_preroll_s = 40.0;
  std::uint64_t seed = 1;
};

/// Most samples (pre-roll included) one experiment holds: about 35 h at 80 Hz.
inline constexpr std::int64_t kMaxExperimentSamples = 10'000'000;

/// Command trajectory (samples x 3, bar) at the sample rate. Samples before
/// `record_from` are a pre-roll: simulated to bring the actuator to its first
/// operating point, not recorded (steering is undefined at rest).
struct Experiment {
  std::string name;
  Eigen::MatrixXd commands;
  Eigen::Index record_from = 0;
};

Experiment staircaseExperiment(const ExperimentOptions& o);
Experiment gridExperiment(const ExperimentOptions& o);
Experiment joystickExperiment(const ExperimentOptions& o);
/// Not the paper's: shows a model's settled error where the grid, which moves
/// one chamber at a time, never goes (both chambers rising together).
Experiment staticMapExperiment(const ExperimentOptions& o);
/// Not the paper's: grid2, then out and back along every diagonal and
/// anti-diagonal of its levels, both chambers moving at once, as a joystick does.
Experiment gridJointExperiment(const ExperimentOptions& o);
/// By name: "staircase1", "grid2", "grid2_joint", "joystick" or "static_map"; throws naming the choices.
Experiment makeExperiment(const std::string& name, const ExperimentOptions& o);

/// Drives the actuator with the experiment and records the standard columns
/// time_s, cmd_1..3, p_1..3, bend_deg, steer_deg with metadata.
io::Log runExperiment(Actuator& actuator, const Experiment& experiment);

}  // namespace plsa::sim
