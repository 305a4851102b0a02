// The baselines plsa's model is compared with, identified from the same
// training logs: the paper's configuration and the global linear OBF.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/identify/pipeline.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// `o` with plsa's extensions off: the paper's configuration (FKcM poles,
/// switched PWL, no play, the outputs as logged, no lag, drift or slow pole);
/// no progress.
IdentifyOptions paperConfiguration(IdentifyOptions o);

/// The training logs as the baselines are fitted to them: the model's inputs,
/// and its outputs less any sensor drift identification took out (as plsa's
/// own were fitted). One matrix per log.
struct BaselineData {
  std::vector<Eigen::MatrixXd> U, Y;
};
BaselineData baselineData(const DioPwlObfModel& m, const IdentifyReport& report, const std::vector<io::Log>& logs);

/// A copy of `m` with one region, coefficients refitted: the global linear OBF baseline.
DioPwlObfModel globalLinearOf(const DioPwlObfModel& m, const std::vector<Eigen::MatrixXd>& U,
                              const std::vector<Eigen::MatrixXd>& Y);

}  // namespace plsa::identify
