// Validation of a DIO-PWL-OBF model on a log: NRMSE fit per output for each
// k-step-ahead horizon and for free simulation, plus the aligned predictions.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "plsa/eval/dio_prediction.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/eval/model_regressors.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::eval {

struct OutputValidation {
  std::string name;
  std::map<int, double> fit_k;  ///< horizon -> fit %
  double fit_sim = 0.0;
  std::map<int, double> rms_k;  ///< horizon -> rms error, output units
  double rms_sim = 0.0;
  double spread = 0.0;  ///< standard deviation of the measured output over the scored samples
  /// horizon -> simulationErrorKept(measured, simulated, scored_from, horizon):
  /// the k-step prediction beats the simulation where this is above 1/2.
  std::map<int, double> sim_error_kept;
  Eigen::VectorXd measured;
  std::map<int, Eigen::VectorXd> predicted_k;  ///< aligned with measured, NaN where undefined
  Eigen::VectorXd simulated;
};

/// Share of the rows of `u` (columns: the model's inputs) with an input
/// outside its training range, in all (`any`) and per input (`each`): each
/// input's own range when the model has input_ranges, else the one over all.
/// For an input the model schedules on a grid of nodes (interpolated
/// partitions), also the shares below its lowest and above its highest node:
/// there the model holds the outer node's dynamics, an extrapolation even
/// where the input stays inside the range the training run spanned (a run
/// recorded from rest spans 0 while its grid may start higher).
struct InputsOutsideTraining {
  double any = 0.0;
  std::vector<double> each;
  std::vector<bool> on_grid;       ///< per input: scheduled on a grid of nodes
  std::vector<double> grid_low;    ///< per input: lowest node (NaN when not on a grid)
  std::vector<double> grid_high;   ///< per input: highest node (NaN when not on a grid)
  std::vector<double> below_grid;  ///< per input: share of rows below the lowest node
  std::vector<double> above_grid;  ///< per input: share of rows above the highest node
  double any_beyond_grid = 0.0;    ///< share of rows with some input beyond its grid
};

/// What a log's first seconds cost an output's free simulation. The
/// simulation starts settled at the first sample's inputs, so a log that
/// does not start at rest shows an error at its start that is the log's, not
/// the model's, and it can last (a yaw registered on it turns the whole run;
/// a model without an output level keeps the offset it starts with). Started
/// and scored `later_s` seconds into the log (SimulationStart::settle_s), the
/// simulation is off by `rms_later` instead of `rms_error`.
struct UnsettledStart {
  std::string output;
  double later_s = 0.0;    ///< the settling time of the later start
  double rms_error = 0.0;  ///< the validated simulation's rms error, output units
  double rms_later = 0.0;  ///< the later-started one's, over the samples it is scored on
  /// A tip-frame model's steering: the share of the samples the later start
  /// leaves out on which the measured tip is straight (bent less than the
  /// yaw registration's least bend). There the angle is the sensor's noise,
  /// degrees wide, so a few such samples explain the error, not an
  /// unsettled start; named when at least 5%.
  double straight_share = 0.0;
};

/// One sentence per unsettled start, for a user: what it is and the
/// settling time (`plsa validate --settle`) that leaves it out.
std::vector<std::string> unsettledStartWarnings(const std::vector<UnsettledStart>& starts);

/// The sensor's yaw over a record as the predictor follows it from the
/// record's start (SensorYaw): each sample's turn from the model's frame into
/// the sensor's (rad; the registered offset from the window's last sample on,
/// and the carried drift), and the offset.
struct SensorYawTrack {
  Eigen::VectorXd angle;
  double offset = 0.0;  ///< the window's registration (the simulation's turn)
  /// Whether the offset was registered: false when the measured tip was bent
  /// less than the minimum over half the window or more (the training yaw kept).
  bool registered = false;
  double bent_share = 0.0;  ///< the window's share of samples bent at least the minimum
};

/// Every fit and rms error, at every horizon and in simulation, is computed
/// on the same samples: from `scored_from` (the first sample every
/// prediction covers: the longest horizon, or the end of the simulation's
/// yaw registration) to the log's end.
struct ValidationResult {
  std::vector<OutputValidation> outputs;
  Eigen::VectorXd time;
  Eigen::Index scored_from = 0;
  InputsOutsideTraining outside_training;  ///< samples with an input outside its training range
  /// The outputs whose simulation, started and scored 5 s later than
  /// settle_s, has at most 0.8 times the rms error (and less by 2% of the
  /// output's standard deviation); empty when none has or the log is too
  /// short to tell (the later start past half of it).
  std::vector<UnsettledStart> unsettled_starts;
  /// A tip_cartesian model's yaw registration (SimulationStart): asked for
  /// (a window and an output level), and the track it followed.
  bool yaw_asked = false;
  SensorYawTrack yaw;
};

/// InputsOutsideTraining of `u` (one column per model input).
InputsOutsideTraining inputsOutsideTraining(const DioPwlObfModel& model, const Eigen::MatrixXd& u);

/// Warnings for a user, one sentence each, per input: the share of samples
/// outside its training range, and below / above its grid's outer nodes.
/// Empty when every sample is inside both.
std::vector<std::string> inputCoverageWarnings(const DioPwlObfModel& model, const InputsOutsideTraining& c);

/// How much of the simulation's error h samples back is still there now:
/// with e = measured - simulated, sum e(t) e(t-h) / sum e(t-h)^2 over the
/// scored samples t >= from (the least-squares gain from e(t-h) to e(t); NaN
/// when e(t-h) is nowhere finite and non-zero). A k-step prediction restarts
/// from the measured output, so it carries the model's error of h samples
/// back into its prediction in full: in the model's frame its error is
/// e(t) - e(t-h) exactly. What persists (an offset, a slow drift, a
/// hysteresis branch) cancels; what changes within the horizon (a transient
/// the model mistimes) counts twice. So its squared error is below the
/// simulation's exactly when this is above 1/2 (approximately, for the angles
/// a tip_cartesian model is scored in).
double simulationErrorKept(const Eigen::VectorXd& measured, const Eigen::VectorXd& simulated, Eigen::Index from, int h);

/// How a free simulation takes up a run. A model with an output_level
/// simulates from the inputs alone and so carries its training run's sensor
/// state; in the tip_cartesian frame the sensor's yaw about the segment axis
/// is part of that state, and no input can tell a new run's. As the
/// method's simulation starts from the measured y(0), a tip_cartesian model
/// registers the run's yaw on its first seconds (bending is untouched: a yaw
/// turns the tip's direction, not its magnitude).
struct SimulationStart {
  /// Seconds at the run's start the yaw is registered on (least-squares
  /// rotation of the predicted onto the measured tip components over them),
  /// at least one sample when > 0; the simulation is scored after them. A
  /// window, not the first sample: one sample registers the model's own error
  /// at the starting state with the yaw (docs/validation.md, 'Simulation
  /// start: yaw registration').
  /// 0: carry the training yaw. Only tip_cartesian models with an
  /// output_level use it.
  double yaw_registration_s = 5.0;
  /// Turn the simulated tip at the sensor yaw rate the training run showed
  /// (training_drift_per_s) over the run, before registering: the model was
  /// fitted with that drift taken out, and a new run's sensor drifts on (as a
  /// gyro's bias does). On the simulator the training estimate (0.0245 deg/s)
  /// is 4x nearer a new run's true rate (0.02) than no drift is
  /// (docs/validation.md, 'Simulation start: yaw registration'). Needs a registration
  /// to anchor the turn. false: simulate the drift-free model.
  bool carry_training_drift = true;
  /// Seconds at the run's start left out of every score, for a run that
  /// does not start at rest: the simulation starts settled at the first
  /// sample's inputs (from the model's output level or the first measured
  /// sample), so a run recorded while the actuator still moved shows an error
  /// at its start that is the log's, not the model's (validateModel names
  /// it: ValidationResult::unsettled_starts). The predictions still run
  /// through them; a yaw registration takes the window after them; a model
  /// without an output level, which simulates from a measured sample, starts
  /// from the one at their end (an unsettled start would leave it a lasting
  /// offset). 0: score from the first sample every prediction covers.
  double settle_s = 0.0;
  /// The yaw registration reads only samples whose measured tip is bent at
  /// least this much (deg), and keeps the training yaw unless they are half
  /// its window or more: at rest the reading's direction is the sensor's
  /// noise and the model's rest tip, not the yaw (SensorYaw).
  double yaw_registration_min_bend_deg = 1.0;
  /// Seconds of memory of a yaw tracked on past the registration window
  /// (SensorYaw tracking, as PredictorOptions::yaw_tracking_s): the k-step
  /// predictions turn by the yaw registered on the samples up to their
  /// anchor, each weighed down by e^-1 per this many seconds, so they follow
  /// the sensor instead of the training drift's extrapolation. The simulation
  /// keeps the window's registration. 0: the window's offset holds and the
  /// drift alone turns on.
  double yaw_tracking_s = 60.0;
};

/// `level`: the model's tip in its frame (modelTip), `ym` the measured one
/// (tip components).
SensorYawTrack trackSensorYaw(const DioPwlObfModel& model, const Eigen::MatrixXd& level, const Eigen::MatrixXd& ym,
                              const SimulationStart& start);
/// An input-side model's tip (model frame) over a record: output_level, the
/// settled response to the first sample and the increments dy since.
Eigen::MatrixXd modelTip(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy);

/// How many samples at a run's start simulateModel registers the yaw on:
/// 0 unless the model is tip_cartesian with an output_level and the window
/// is > 0, else the window's samples, at least one. Throws for a window that
/// is negative or not finite.
Eigen::Index yawRegistrationSamples(const DioPwlObfModel& model, const SimulationStart& start);

/// The samples at a run's start SimulationStart::settle_s leaves out of the
/// scores (a yaw registration starts after them). Throws for a settling time
/// that is negative or not finite.
Eigen::Index settleSamples(const DioPwlObfModel& model, const SimulationStart& start);

/// The sensor yaw rate (deg/s) simulateModel turns the tip at: the model's
/// training steering drift when `start` carries it and registers the yaw
/// (yawRegistrationSamples > 0), else 0.
double carriedYawRate(const DioPwlObfModel& model, const SimulationStart& start);

/// Free simulation of every output from the inputs, in the model's output
/// frame (y too): from the model's output_level when it has one (its yaw
/// registered as `start` says, from the first sample after the window),
/// else from the first measured sample (samples 1..T-1). `dy` is modelIncrements(model, u).
std::vector<AlignedPrediction> simulateModel(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                             const Eigen::MatrixXd& y, const Eigen::MatrixXd& dy,
                                             const SimulationStart& start = {});

/// Every output's predictions in the log's frame (y as logged): key k >= 1
/// the k-step-ahead predictions, key 0 the free simulation when asked for.
/// A tip_cartesian model's steering is put on the branch (+-360 deg) of the
/// measured angle at the same sample, so it is compared as an angle (the
/// predictor writes it on the branch of the angle it starts from).
std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation = true,
                                                             const SimulationStart& start = {});
/// The same from increments already computed (`dy` = modelIncrements(model, u)).
std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const Eigen::MatrixXd& dy,
                                                             const SimulationStart& start = {});

/// How far an output's free simulation leaves the range its measurements
/// span, over the scored samples (from scored_from). A model that extrapolates
/// (inputs beyond its grid, another kind of run than it was trained on) can
/// drift or diverge in simulation while its k-step predictions, re-anchored on
/// every measurement, still look fine: this names it.
struct SimulationDeparture {
  std::string output;
  double measured_low = 0.0, measured_high = 0.0;  ///< the measured output's range
  double farthest = 0.0;      ///< largest distance of the simulation outside that range, output units
  double share = 0.0;         ///< farthest / (measured_high - measured_low)
  double first_time_s = 0.0;  ///< when the simulation first left the range by more than the tolerance
};

/// The outputs whose free simulation leaves the measured range by more than
/// `tolerance` times its width (a model that follows the run stays inside,
/// give or take its error); empty when none does. Throws for a tolerance that
/// is not positive and finite.
std::vector<SimulationDeparture> simulationDepartures(const ValidationResult& v, double tolerance = 0.5);

/// One sentence per departure, for a user.
std::vector<std::string> simulationWarnings(const std::vector<SimulationDeparture>& departures);

/// Throws naming the missing column, the bad or repeated horizon, a registration
/// window as long as the log, a time gap, or a sample time (from `time_s`, when
/// the log has it) 2% or more off the model's, or a settle_s that is negative,
/// not finite or leaves fewer than 2 samples to score.
ValidationResult validateModel(const DioPwlObfModel& model, const io::Log& log, const std::vector<int>& horizons,
                               const SimulationStart& start = {});

/// Measured vs predicted as a log: time_s, then per output <name>, <name>_k<h>..., <name>_sim,
/// over the scored samples (from scored_from): the fits recomputed from it are the ones printed.
io::Log predictionLog(const ValidationResult& v);

}  // namespace plsa::eval
