// Validation of a DIO-PWL-OBF model on a log: NRMSE fit per output for each
// k-step-ahead horizon and for free simulation, plus the aligned predictions.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "plsa/eval/dio_prediction.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa {

struct OutputValidation {
  std::string name;
  std::map<int, double> fit_k;  ///< horizon -> fit %
  double fit_sim = 0.0;
  Eigen::VectorXd measured;
  std::map<int, Eigen::VectorXd> predicted_k;  ///< aligned with measured, NaN where undefined
  Eigen::VectorXd simulated;
};

struct ValidationResult {
  std::vector<OutputValidation> outputs;
  Eigen::VectorXd time;
  double input_outside_range = 0.0;  ///< share of samples outside the model's training input range
};

/// Free simulation of every output from the inputs, for samples 1..T-1, in
/// the model's output frame (y too): from the model's output_level when it
/// has one, else from the first measured sample. `dy` is modelIncrements(model, u).
std::vector<AlignedPrediction> simulateModel(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                             const Eigen::MatrixXd& y, const Eigen::MatrixXd& dy);

/// Every output's predictions in the log's frame (y as logged): key k >= 1
/// the k-step-ahead predictions, key 0 the free simulation when asked for.
/// A tip_cartesian model's steering is put on the branch of the measured
/// angle its prediction starts from (simulation: of its own previous value).
std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation = true);
/// The same from increments already computed (`dy` = modelIncrements(model, u)).
std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const Eigen::MatrixXd& dy);

/// Throws naming the missing column or the bad horizon.
ValidationResult validateModel(const DioPwlObfModel& model, const io::Log& log, const std::vector<int>& horizons);

/// Measured vs predicted as a log: time_s, then per output <name>, <name>_k<h>..., <name>_sim,
/// from the first sample every prediction covers.
io::Log predictionLog(const ValidationResult& v);

}  // namespace plsa
