// The predictor as an LCM node: actuator state in, n-step-ahead predictions
// out every tick, and a status message with rejected-sample counts and the
// latency of update+predict (p50/p99/max) once a second.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::lcm {

/// Longest horizon the node publishes, in seconds of model time. Each tick
/// sends the whole trajectory, and the predictor preallocates per step; far
/// past a controller's horizon a typo would cost megabytes every tick.
inline constexpr double kMaxPublishedHorizonS = 60.0;

struct PredictorNodeOptions {
  std::string url;
  std::vector<int> horizons{40, 80};
  std::string state_channel = "PLSA_STATE";
  std::string prediction_channel = "PLSA_PREDICTION";
  std::string status_channel = "PLSA_STATUS";
  /// SCHED_FIFO priority for the node's thread where permitted (0: none);
  /// memory is locked and pre-faulted either way (plsa/predict/realtime_thread.hpp).
  int realtime_priority = 40;
};

struct PredictorNodeStats {
  std::int64_t states = 0;
  std::int64_t predictions = 0;
  std::int64_t rejected = 0;
  std::int64_t deadline_misses = 0;  ///< states whose update, predictions and publishing took over a sample time
  std::string realtime;              ///< what real-time scheduling the node got
};

/// Runs until `stop` is set. Its status (once a second) counts states,
/// predictions and rejections by reason, the latency of update+predict
/// (p50/p99/max), deadline misses (a state's work over one sample time) and
/// the arrival jitter of states (p99 of |interval - sample time|). Throws std::invalid_argument for a horizon below 1,
/// given twice or longer than kMaxPublishedHorizonS (before LCM is opened), if the model's
/// columns cannot be read from actuator-state messages (p_i, cmd_i,
/// bend_deg, steer_deg), std::runtime_error if LCM cannot be set up.
PredictorNodeStats runPredictorNode(const DioPwlObfModel& model, const PredictorNodeOptions& options,
                                    const std::atomic<bool>& stop);

}  // namespace plsa::lcm
