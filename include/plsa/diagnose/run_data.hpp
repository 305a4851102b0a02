// One recorded run as the diagnosis sees it: chamber commands (bar) in, the
// tip's bending vector (or any two outputs) out, chamber pressures when they
// were measured. Built from a log with clear errors for anything unusable.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/io/csv_log.hpp"
#include "plsa/io/standard_columns.hpp"

namespace plsa::diagnose {

/// How the real outputs relate to the simulator's tip.
enum class OutputMap {
  kAngles,  ///< outputs are bend and steer angles (deg), compared as the bending vector
  kAffine,  ///< outputs are an unknown affine image of the bending vector (e.g. tip position), fitted
};

/// How a run's recording began: with the actuator vented and at rest (as a
/// user records: valves open, logger started, then the commands), or settled
/// at its first command. The simulator replays each the same way.
enum class RunStart {
  kAtRest,   ///< replayed from rest, no pre-roll
  kSettled,  ///< replayed after holding the first command until settled (settlingTime), unrecorded
  kAuto,     ///< runFromLog: decided from the data (detectRunStart)
};

struct RunColumns {
  std::vector<std::string> inputs = io::standard_columns::commands();  ///< 1 to 3 chambers; the rest get 0
  std::vector<std::string> outputs = io::standard_columns::tipAngles();
  std::vector<std::string> pressures = io::standard_columns::pressures();  ///< used when every one is present
  double input_scale = 1.0;                                                ///< bar per input unit
  OutputMap map = OutputMap::kAngles;
  RunStart start = RunStart::kAuto;
};

struct RunData {
  std::string name;
  double sample_time_s = 0.0;
  Eigen::MatrixXd commands;            ///< samples x 3, bar
  Eigen::MatrixXd outputs;             ///< samples x 2: bending vector (deg) for kAngles, raw outputs for kAffine
  Eigen::MatrixXd pressures;           ///< samples x 3 (bar) or no columns
  RunStart start = RunStart::kAtRest;  ///< kAtRest or kSettled (of the lead-in's first command when there is one)
  /// Commands replayed before the run, unrecorded (samples x 3, bar; none by
  /// default): the held-out part of a single run replays the part before it,
  /// so the simulator carries the state the run had built up there
  /// (hysteresis, creep, a sensor's drift) instead of starting afresh.
  Eigen::MatrixXd lead_in;

  Eigen::Index samples() const { return commands.rows(); }
  bool hasPressures() const { return pressures.cols() == 3; }
};

/// Throws std::invalid_argument naming the run and the problem (missing
/// column, NaN, negative or out-of-range command, too few samples, no time).
RunData runFromLog(const io::Log& log, const RunColumns& columns, double max_pressure_bar);

/// Whether `run` starts at rest or settled: at rest when its first command
/// is (nearly) zero, when the measured pressure of the chamber with the
/// largest first command starts more than 20% away from it, or (without pressures, outputs as angles) when its first
/// bending vector is under 15% of its median length; settled when the
/// pressures or the bending show the first command already applied; at
/// rest when nothing tells (affine outputs without pressures), as users
/// record.
RunStart detectRunStart(const RunData& run, OutputMap map);

/// Bend and steer (deg) -> bending vector (deg): steer wraps, the vector does not.
Eigen::MatrixXd bendingVector(const Eigen::VectorXd& bend_deg, const Eigen::VectorXd& steer_deg);

/// The first (1 - heldout_fraction) of a run and the rest, the rest with the
/// first part as its lead-in.
std::pair<RunData, RunData> splitByTime(const RunData& run, double heldout_fraction);

}  // namespace plsa::diagnose
