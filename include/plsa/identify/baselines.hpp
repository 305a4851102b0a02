// The baselines plsa's model is compared with, identified from the same
// training logs: the paper's configuration and the global linear OBF.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/identify/coefficient_fit.hpp"
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
/// own were fitted), one matrix per log; and how the model's slow pole, if
/// it kept one, was tied.
struct BaselineData {
  std::vector<Eigen::MatrixXd> U, Y;
  SlowModeTie slow_mode;
};
BaselineData baselineData(const DioPwlObfModel& m, const IdentifyReport& report, const std::vector<io::Log>& logs);

/// A copy of `m` with one region, coefficients refitted on `training` (its
/// slow pole tied as the model's): the global linear OBF baseline.
DioPwlObfModel globalLinearOf(const DioPwlObfModel& m, const BaselineData& training);

}  // namespace plsa::identify
