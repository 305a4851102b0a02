// Several models' predictions of one log, every model scored over the same
// samples: the comparisons `plsa demo`, `crossval`, `generalise` and
// `identify --structure` print.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/eval/arx.hpp"
#include "plsa/eval/validation.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::eval {

/// Full-length predictions (NaN where a model predicts nothing) per horizon
/// (0 = free simulation), per output.
struct ModelPredictions {
  std::string name;
  std::vector<std::map<int, Eigen::VectorXd>> by_output;
};

ModelPredictions predictDio(const std::string& name, const DioPwlObfModel& m, const Eigen::MatrixXd& u,
                            const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                            const SimulationStart& start = {});
/// `sim_drift_per_s` (empty, or one rate per output): an output drift added to
/// the simulation from the first sample, for an ARX fitted with it taken out.
ModelPredictions predictArx(const std::string& name, const ArxModel& m, const Eigen::MatrixXd& u,
                            const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                            const std::vector<double>& sim_drift_per_s = {}, double sample_time_s = 0.0);

/// One model's score on one output and horizon.
struct CommonScore {
  double fit = 0.0;     ///< NRMSE fit %
  double rms = 0.0;     ///< rms error, output units
  double spread = 0.0;  ///< the measured output's standard deviation over the same samples
};

/// The first sample every model predicts at every horizon and in simulation.
Eigen::Index commonScoringStart(const std::vector<ModelPredictions>& models);

/// scores[model][output][horizon], all over the same samples: from
/// commonScoringStart(models) to the end.
std::vector<std::vector<std::map<int, CommonScore>>> commonScores(const std::vector<ModelPredictions>& models,
                                                                  const Eigen::MatrixXd& y);

}  // namespace plsa::eval
