// Replaying real runs through the simulator and calibrating its parameters
// to them (NLopt, bounded, derivative-free): the gap measure every later
// figure uses, and the fit that keeps a plain parameter mismatch from being
// blamed on a missing effect.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "plsa/diagnose/run_data.hpp"
#include "plsa/sim/actuator.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::diagnose {

/// What the simulator says for a run: its outputs in the run's output space
/// (bending vector, deg; with the sensor noise its configuration has) and
/// chamber pressures.
struct SimTrace {
  Eigen::MatrixXd outputs;    ///< samples x 2
  Eigen::MatrixXd pressures;  ///< samples x 3
};

/// Drives the simulator with `commands` (samples x 3, bar) at its own sample
/// rate, after holding the first command for `preroll_s` unrecorded (0: from
/// rest; settlingTime(config): settled as the diagnosis replays); sensor
/// noise as configured, seeded with `seed`. The first `unrecorded` rows are
/// stepped but not recorded (the trace has the rest). `branch`: the sensor's
/// folded reading, or unfolded past 180 deg of bend.
SimTrace replayCommands(const sim::SimConfig& config, const Eigen::MatrixXd& commands, std::uint64_t seed,
                        double preroll_s, Eigen::Index unrecorded = 0,
                        sim::ReadingBranch branch = sim::ReadingBranch::kSensor);

/// The reading a run's outputs are compared with: angles are the sensor's,
/// folded past 180 deg of bend as a real sensor's are; an affine image of
/// the bending vector (a tip position) does not fold, so it is fitted to the
/// unfolded reading.
sim::ReadingBranch readingBranchFor(OutputMap map);

/// How long a run that began settled is replayed at its first command,
/// unrecorded, so that the simulator's states are settled too: 3 s (the
/// bending mode and the chambers), or five of its creep's slowest time
/// constants when creep is on (a log recorded after a long hold holds no
/// creep transient), at most 60 s.
double settlingTime(const sim::SimConfig& config);

/// replayCommands at the run's sample rate with the simulator's own sensor
/// noise off: from rest, or after settlingTime(config) at the first command
/// when the run started settled (RunData::start); the run's lead-in, if any,
/// replayed unrecorded first; read on readingBranchFor(map).
SimTrace simulateRun(const sim::SimConfig& config, const RunData& run, OutputMap map);

/// Affine output map y = [v 1] * M (3 x 2) for OutputMap::kAffine; identity otherwise.
struct OutputFit {
  Eigen::Matrix<double, 3, 2> M = (Eigen::Matrix<double, 3, 2>() << 1, 0, 0, 1, 0, 0).finished();
  Eigen::MatrixXd apply(const Eigen::MatrixXd& v) const;
};

/// The gap between runs and the simulator, normalised: squared residual over
/// the outputs' variance (1 = no better than the mean), pressures (when
/// measured) weighted by `pressure_weight` the same way.
struct Gap {
  double outputs = 0.0;    ///< normalised mean squared residual of the outputs
  double pressures = 0.0;  ///< the same for chamber pressures (0 without them)
  double total = 0.0;      ///< outputs + pressure_weight * pressures
  double percent() const { return 100.0 * std::sqrt(std::max(0.0, total)); }  ///< gap in % (like 100 - NRMSE fit)
};

struct GapOptions {
  double pressure_weight = 0.5;
  OutputMap map = OutputMap::kAngles;
};

/// Gap of a configuration on runs; with kAffine the map is fitted here when
/// `fit` is non-null and not frozen, else `fit` is used as given.
Gap measureGap(const sim::SimConfig& config, const std::vector<RunData>& runs, const GapOptions& options,
               OutputFit* fit = nullptr, bool refit = true);

/// The noise floor of the same gap measure, estimated from the runs alone
/// (second differences: a smooth signal has little, white noise 6 sigma^2).
Gap noiseFloor(const std::vector<RunData>& runs, const GapOptions& options);

/// The share of the gap above the noise floor that `after` closes, %: gaps
/// are mean squares, so the noise adds to the modelling error and no
/// simulator gets below it; 100 reaches the floor. NaN when `before` is not
/// over twice the noise floor (in %): nothing a model could close.
double shrinkAboveNoise(const Gap& before, const Gap& after, const Gap& noise);

struct CalibrationOptions {
  int max_evaluations = 150;
  /// ...raised to this many per calibrated parameter: BOBYQA spends 2n + 1
  /// runs on its first model alone, and a second kept effect brings a
  /// calibration to 13 parameters, where 150 runs stopped short (a lag +
  /// stiffening pair then missed stiffening; docs/diagnosis.md). 0: off.
  int evaluations_per_parameter = 20;
  double initial_step = 0.15;  ///< in the normalised (0..1, log for wide positive ranges) parameter space
  GapOptions gap;
  std::function<void(int evaluation, double best_total)> progress;  ///< optional, every 25 evaluations
  /// Parameters ("module.name", of the calibrated modules) held at their
  /// start values: a start from one part of an effect's family (the
  /// hysteresis's smooth element alone) calibrates that part only.
  /// runDiagnosis sets it for each start and refuses it set in its options.
  std::vector<std::string> held;
  /// The simulator's integrator (sim::integratorNames()) where the diagnosis
  /// calibrates at an internal step coarser than the configured one (its
  /// screening and calibration steps); every gap it reports is measured at
  /// the configured step and integrator. "exponential" follows a 0.1 ms run
  /// closer at 6.25 ms than "euler" does at 1 ms (SimIntegration tests).
  std::string coarse_integrator = "euler";
};

struct CalibrationResult {
  sim::SimConfig config;  ///< with the fitted values
  Gap train_gap;
  OutputFit fit;
  int evaluations = 0;
  std::vector<std::pair<std::string, double>> values;  ///< "module.name" -> fitted value, or the held one
  std::vector<std::string> held;                       ///< the options' held parameters
};

/// Fits every parameter of `modules` ("nominal" and effect names; each effect
/// must be enabled in `start`) to the training runs by bounded BOBYQA from
/// the start values, except those `options.held` names. Throws
/// std::invalid_argument for unknown modules and held names that are none
/// of their parameters.
CalibrationResult calibrate(const sim::SimConfig& start, const std::vector<std::string>& modules,
                            const std::vector<RunData>& train, const CalibrationOptions& options);

}  // namespace plsa::diagnose
