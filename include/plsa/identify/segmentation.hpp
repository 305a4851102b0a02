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

/// A piecewise-constant reference recovered from measured inputs (pressures
/// logged without their commands): per column, the runs that stay within
/// `noise_multiple` times the column's noise (robust, from its sample-to-
/// sample differences; at least resolution / 2) of their own mean; a run
/// held at least `min_hold` samples is a plateau, and its level is the mean
/// of the plateaus whose means lie within the same band (one commanded level
/// read once); a shorter run (a transition, a spike) takes the level of the
/// plateau after it (the last one's at the end), so the reference steps
/// where the input starts to move, as a command does. A column whose
/// plateaus cover less than half its samples (a random walk, an excitation
/// that holds now and then by chance) is returned as it is.
Eigen::MatrixXd plateauReference(const Eigen::MatrixXd& inputs, Eigen::Index min_hold, double resolution,
                                 double noise_multiple = 5.0);

/// The distinct levels each input holds for at least `min_length` samples
/// (rounded to `resolution`), sorted: the experiment's reference pressures.
std::vector<std::vector<double>> referenceLevels(const Eigen::MatrixXd& reference, double resolution,
                                                 Eigen::Index min_length);

}  // namespace plsa::identify
