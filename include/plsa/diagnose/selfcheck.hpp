// The diagnosis checked on data whose effect is known but withheld: "real"
// data from the simulator with one or two effects switched on (random
// parameters, sometimes another formulation, nominal physics perturbed),
// diagnosed blind by a simulator that has every effect switched off.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "plsa/diagnose/diagnosis.hpp"

namespace plsa::diagnose {

struct SelfcheckOptions {
  std::vector<std::string> effects;  ///< single-effect cases; empty: all seven
  int seeds_per_effect = 2;          ///< odd seeds generate the data with another law than the candidate's
  std::vector<std::pair<std::string, std::string>> pairs = {
      {"hysteresis", "creep"}, {"deadzone", "coupling"}, {"pneumatic_lag", "stiffening"}};
  int null_cases = 2;
  double nominal_perturbation = 0.15;  ///< each nominal parameter scaled by 1 +- this (uniform)
  double train_s = 60.0, heldout_s = 40.0;
  std::uint64_t seed = 1;
  DiagnoseOptions diagnose;
  std::function<void(const std::string&)> log;
  bool verbose = false;  ///< pass each diagnosis's own progress lines to `log`
};

struct SelfcheckCase {
  std::string name;
  std::vector<std::string> withheld;  ///< empty: the null case
  std::string formulation;            ///< of the withheld effect(s) in the "real" data
  std::vector<std::pair<std::string, double>> truth;  ///< its parameters
  std::vector<std::string> selected;
  std::vector<std::string> top2;     ///< round-1 ranking, best two
  double gap_before = 0, gap_after = 0, noise = 0;
  double true_effect_shrink = 0;     ///< single: the withheld effect's own round-1 shrink; pair: overall
  bool pass = false;
  double elapsed_s = 0;
};

struct SelfcheckResult {
  std::vector<SelfcheckCase> cases;
  std::vector<std::string> labels;               ///< rows/cols of the confusion matrix: effects, then "none"
  std::vector<std::vector<int>> confusion;       ///< [truth][top-1 selected]
  int single_cases = 0, single_top1 = 0, pair_cases = 0, pair_top2 = 0, null_cases = 0, null_clean = 0;
  double min_true_shrink = 0, median_true_shrink = 0;
  bool targets_met = false;
  std::string summary() const;  ///< the printed table: cases, confusion matrix, targets
};

/// The random piecewise-constant (sometimes ramped) multi-chamber excitation
/// used for self-check runs: holds of 0.6-3 s, zero or 0.03-0.36 bar per chamber.
Eigen::MatrixXd excitationCommands(double duration_s, double sample_rate_hz, std::uint64_t seed);

SelfcheckResult runSelfcheck(const SelfcheckOptions& options);

}  // namespace plsa::diagnose
