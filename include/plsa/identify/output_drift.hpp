// A slow drift of the output sensor, linear in time, estimated from training
// logs and taken out of them before the coefficients are fitted, so that the
// model learns the actuator rather than the sensor's wander: a tip sensor's
// yaw (steering angle) for tip_cartesian models, each output's trend otherwise.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/eval/model_regressors.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// Drift rates per logged output (output units per second) about a reference
/// time, where the correction is zero: the logs' mean sample time, so the
/// model keeps the sensor's average state over the training run. One trend
/// runs through every log's time stamps: on one clock, a drift since
/// power-up; on clocks that restart per log, a trend within each log.
struct OutputDrift {
  std::vector<double> rate;  ///< per logged output; tip_cartesian: {0, steering's yaw rate}
  double reference_time_s = 0.0;
  bool none() const {
    for (double r : rate)
      if (r != 0.0) return false;
    return true;
  }
};

/// The mean of every sample time in `t`.
double meanSampleTime(const std::vector<Eigen::VectorXd>& t);

/// Y (logged frame) less the drift: y_o(t) - rate_o (t - reference_time_s).
/// A tip_cartesian yaw is a shift of the steering angle, so this is exact there too.
std::vector<Eigen::MatrixXd> removeOutputDrift(const std::vector<Eigen::MatrixXd>& Y,
                                               const std::vector<Eigen::VectorXd>& t, const OutputDrift& drift);

/// Estimates the drift on an input-side model's structure: fits it, regresses
/// the level residual (y - output_level - modelLevels) on the drift's
/// signature, takes that out and refits, `iterations` times, because the
/// first fits absorb part of a drift wherever the inputs trend with time.
/// Levels, not increments: a drift of a few hundredths of a degree per
/// second is buried in the sensor noise of 80 Hz increments.
/// Empty records are skipped; data that cannot show a drift (a tip at the
/// origin, no time span) give rate 0. Throws naming the problem (output-side
/// model, mismatched records). `weights` (as in fitCoefficients) restricts
/// the fits and the regression to the samples they weigh.
OutputDrift estimateOutputDrift(const DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                const std::vector<Eigen::MatrixXd>& Y, const std::vector<Eigen::VectorXd>& t,
                                const CoefficientFitOptions& options = {}, int iterations = 3,
                                const SampleWeights& weights = {});

}  // namespace plsa::identify
