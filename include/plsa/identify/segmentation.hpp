// Step 1 of the paper's Table I: cut a staircase / grid log into local data
// sets, one per step of one input (SIMO per input), with its direction.
#pragma once

#include <vector>

#include <Eigen/Dense>

namespace plsa::identify {

struct LocalDataSet {
  Eigen::Index begin = 0;  ///< first sample after the step
  Eigen::Index end = 0;    ///< one past the last sample before the next step
  int input = 0;           ///< the input that moved
  double from = 0.0;       ///< its level before the step
  double to = 0.0;         ///< its level after
  bool rising() const { return to > from; }
};

/// Steps are changes of more than `min_step` in a piecewise-constant
/// reference (commands). Segments shorter than `min_length` samples or where
/// several inputs moved at once are dropped (they are not local step responses).
std::vector<LocalDataSet> segmentSteps(const Eigen::MatrixXd& reference, double min_step, Eigen::Index min_length);

/// The distinct levels each input holds for at least `min_length` samples
/// (rounded to `resolution`), sorted: the experiment's reference pressures.
std::vector<std::vector<double>> referenceLevels(const Eigen::MatrixXd& reference, double resolution,
                                                 Eigen::Index min_length);

}  // namespace plsa::identify
