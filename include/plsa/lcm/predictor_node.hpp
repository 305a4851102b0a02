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
};

struct PredictorNodeStats {
  std::int64_t states = 0;
  std::int64_t predictions = 0;
  std::int64_t rejected = 0;
};

/// Runs until `stop` is set. Throws std::invalid_argument for a horizon below 1,
/// given twice or longer than kMaxPublishedHorizonS (before LCM is opened), if the model's
/// columns cannot be read from actuator-state messages (p_i, cmd_i,
/// bend_deg, steer_deg), std::runtime_error if LCM cannot be set up.
PredictorNodeStats runPredictorNode(const DioPwlObfModel& model, const PredictorNodeOptions& options,
                                    const std::atomic<bool>& stop);

}  // namespace plsa::lcm
