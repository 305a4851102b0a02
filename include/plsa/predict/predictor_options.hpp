// What the real-time predictor is asked for and what it answers: options
// (set-up) and status codes (every real-time call).
#pragma once

namespace plsa {

/// Results of the real-time calls: 0 is OK; positive values accepted the
/// sample and say what else happened; negative values rejected it (state kept).
enum class PredictorStatus : int {
  kOk = 0,
  kTimeGap = 1,             ///< time jumped ahead: the filters restarted at rest at this sample
  kClockStepBack = 2,       ///< time went back for kClockStepSamples samples in a row: restarted at rest
  kNotFinite = -1,          ///< a NaN or Inf in the sample (or the plan): rejected, state kept
  kInputOutOfRange = -2,    ///< an input (or a planned one) outside the accepted range: rejected, state kept
  kTimeNotIncreasing = -3,  ///< time did not advance: rejected, state kept
  kHorizonOutOfRange = -5,  ///< horizon below 1 (sensitivity: 2) or above the capacity set at construction
  kHorizonTooLong [[deprecated("use kHorizonOutOfRange")]] = kHorizonOutOfRange,
  kBadShape = -6,             ///< plan or output buffer of the wrong size
  kNotReady = -7,             ///< predict() before the first accepted sample
  kUnsupported = -8,          ///< not available for this model (sensitivity: no modal form)
  kPredictionNotFinite = -9,  ///< the prediction overflowed (a model whose numbers are out of all proportion)
};

/// What Predictor::sensitivity writes. Column (s, j) of the Jacobian moves
/// only in the rows after plan step s (h > s); its rows up to the step are
/// structurally zero.
enum class JacobianFill {
  kWhole,       ///< every entry, the structural zeros too
  kMovingRows,  ///< only rows h > s of each column (s, j); the rest is left as it is: zero the matrix
                ///< once and pass the same one every tick (half the entries are not written)
};

inline const char* toString(PredictorStatus s) {
  switch (s) {
    case PredictorStatus::kOk:
      return "ok";
    case PredictorStatus::kTimeGap:
      return "time gap: filters restarted";
    case PredictorStatus::kClockStepBack:
      return "clock stepped back: filters restarted";
    case PredictorStatus::kNotFinite:
      return "sample has NaN or Inf";
    case PredictorStatus::kInputOutOfRange:
      return "input (or a planned one) outside the accepted range";
    case PredictorStatus::kTimeNotIncreasing:
      return "time did not increase";
    case PredictorStatus::kHorizonOutOfRange:
      return "horizon below 1 (sensitivity: 2) or above capacity";
    case PredictorStatus::kBadShape:
      return "buffer of the wrong size";
    case PredictorStatus::kNotReady:
      return "no sample yet";
    case PredictorStatus::kUnsupported:
      return "not available for this model";
    case PredictorStatus::kPredictionNotFinite:
      return "prediction is not finite (the model's numbers overflow)";
  }
  return "unknown";
}

/// Whether a status means the sample was taken (possibly with a restart).
inline bool accepted(PredictorStatus s) noexcept { return static_cast<int>(s) >= 0; }

/// Samples in a row, each later than the one before but all before the last
/// accepted time, after which the clock is taken to have stepped back (a wall
/// clock set back, or one sample stamped far in the future before them): the
/// filters restart at rest at the third. One stale or duplicated sample is
/// rejected; a clock that stands still never restarts anything.
inline constexpr int kClockStepSamples = 3;

/// Largest predict() capacity: set-up tabulates every mode's power sums up to
/// it (100000 samples, about 21 min at 80 Hz; 800 KB per mode).
inline constexpr int kMaxPredictorHorizon = 100000;

struct PredictorOptions {
  int max_horizon = 400;        ///< capacity of predict(), preallocated
  double input_margin = 0.25;   ///< accepted inputs: model range widened by this share of it
  double max_gap_factor = 2.5;  ///< a time step above this many sample times is a gap
  bool simulate = false;        ///< free simulation: the output is never reset to a measurement
  /// tip_cartesian models: seconds after each start over which the turn
  /// between the model's frame and the sensor's is registered (SensorYaw);
  /// predictions then add the model's increments turned into the sensor's
  /// frame, turning on at the training run's yaw drift. 0: the model's frame
  /// (the training sensor's yaw at its mean time). Not in simulation mode.
  double yaw_registration_s = 5.0;
  /// Only samples whose measured tip is bent at least this much (deg) are
  /// registered on, and unless they are half the window or more the model's
  /// frame is kept: at rest the reading's direction is the sensor's noise,
  /// not its yaw (SensorYaw).
  double yaw_registration_min_bend_deg = 1.0;
  /// Seconds of memory of the yaw tracked on past the window (SensorYaw
  /// tracking): every sample whose tip is bent is registered on, each earlier
  /// one weighed down by e^-1 per this many seconds, so the predictions follow
  /// the sensor's yaw over a session of any length instead of extrapolating
  /// the training run's drift (docs/predictor.md, 'The sensor's yaw'). Costs
  /// update() one evaluation of the increments per tick. 0: the window's
  /// offset holds and the drift alone turns on.
  double yaw_tracking_s = 60.0;
  /// Run in modal form when the model allows it (false: always step the banks
  /// as state-space filters, the slower reference the modal form is checked
  /// and measured against).
  bool modal = true;
};

}  // namespace plsa
