// The paper's Table I from logs to a model: segment, local LTI fits, pole
// clustering per input-output pair, OBF banks, DIO-PWL partition, coefficients.
// Every stage reports what it did and what it rejected.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/pole_clustering.hpp"
#include "plsa/io/csv_log.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa {

struct IdentifyOptions {
  std::vector<std::string> inputs = {"p_1", "p_2", "p_3"};
  std::vector<std::string> outputs = {"bend_deg", "steer_deg"};
  /// Piecewise-constant references to segment on; empty: cmd_1..3 when present, else the inputs.
  std::vector<std::string> reference;
  int poles_per_pair = 5;
  int local_order = 1;
  std::string pole_method = "fkcm";  ///< fkcm | fcm | kmeans | global
  ClusteringOptions clustering;
  /// Levels per scheduling input when the log has no staircase (quantile grid).
  int quantile_levels = 3;
  bool direction_split = false;
  /// "interpolated" (coefficients blended between grid nodes) or "switched" (paper).
  std::string scheduling = "interpolated";
  double step_threshold = 0.005;  ///< a reference change above this is a step
  double max_gap_factor = 2.5;    ///< tolerated sample-time gap (dropped samples)
  double window_s = 8.0;          ///< local windows when the log has no steps
  CoefficientFitOptions coefficients;
  std::function<void(const std::string&)> progress;  ///< one line per stage
};

struct PairPoles {
  int input = 0, output = 0;
  std::vector<std::complex<double>> identified;  ///< usable local poles
  int rejected = 0;
  std::vector<std::string> rejections;  ///< why, one line each
  ClusteringResult chosen;
};

struct IdentifyReport {
  int segments = 0;
  bool used_windows = false;  ///< no staircase: poles from local windows
  std::vector<PairPoles> pairs;
  CoefficientFitReport coefficients;
  std::vector<std::string> lines;  ///< everything the progress callback saw
};

/// Throws std::invalid_argument / std::runtime_error naming the log and the problem.
DioPwlObfModel identifyModel(const std::vector<io::Log>& logs, const IdentifyOptions& options,
                             IdentifyReport* report = nullptr);

/// Partition helpers, exposed for tools and tests.
std::vector<double> midpoints(const std::vector<double>& levels);
std::vector<double> quantileBreakpoints(std::vector<double> values, int levels);

}  // namespace plsa
