// Step 7: the DIO-PWL-OBF coefficients by regularised least squares over all
// samples, each sample feeding its region's block. Each region is pulled
// toward the global linear solution; regions with too little data are
// reported and take their nearest fitted neighbours' coefficients.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa {

struct CoefficientFitOptions {
  double ridge = 1e-6;              ///< on the global solution, relative to the regressors' scale
  double pull_to_global = 1e-2;     ///< ridge of each region toward the global solution (relative)
  int min_samples_per_parameter = 4;
};

struct CoefficientFitReport {
  int regions_fitted = 0;
  int regions_fallback = 0;
  std::vector<std::string> notes;  ///< one line per fallback region, in words
};

/// Fills model.coefficients and model.region_fits. The model's poles,
/// partition, inputs and outputs must be set; U[r], Y[r] are records (T x n),
/// Y in the log's frame (converted to the model's output_frame here).
CoefficientFitReport fitCoefficients(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                     const std::vector<Eigen::MatrixXd>& Y, const CoefficientFitOptions& options = {});

/// Input-side models: output_level as the mean of y - modelLevels over every
/// training sample, so that free simulation needs no measured start.
void fitOutputLevel(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& Y);

}  // namespace plsa
