// Sim-to-real gap diagnosis: calibrate the simulator's nominal physics to the
// training data, show where the held-out gap lies, try every switched-off
// candidate effect (calibrated too) and rank them by held-out shrinkage, then
// keep effects by forward selection while they beat the noise level by a
// stated margin. Every "how far" figure is on held-out data.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "plsa/diagnose/calibration.hpp"
#include "plsa/diagnose/gap_breakdown.hpp"
#include "plsa/diagnose/run_data.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::diagnose {

struct DiagnoseOptions {
  CalibrationOptions calibration;
  int nominal_evaluations = 300;   ///< the nominal fit gets more: it is the baseline everything is judged against
  double heldout_fraction = 0.3;   ///< with a single run: its last part is held out
  double margin = 1.0;             ///< keep an effect only if it shrinks the held-out gap by more than margin x noise floor
  /// ...and by at least this share of the gap (after re-calibrating without
  /// it): form mismatch leaves a structured residual that any added freedom
  /// trims by a few percent, on held-out data too.
  double min_relative = 0.15;
  int max_selected = 3;
  std::vector<std::string> candidates;  ///< empty: every effect switched off in the simulator
  /// A switched-on candidate takes its flexible law where the simulator has
  /// one (stiffening and pneumatic_lag: "power", whose exponent spans the
  /// fixed laws), since real hardware follows none of the fixed laws exactly.
  /// False: each candidate keeps the formulation its configuration names.
  bool flexible_laws = true;
  int threads = 2;
  std::function<void(const std::string&)> log;  ///< progress lines
};

struct CandidateResult {
  std::string effect;
  std::string formulation;       ///< the law it was calibrated with
  int round = 1;                 ///< forward-selection round it was tried in
  Gap heldout_before, heldout_after, train_after;
  double shrink_percent = 0.0;   ///< 100 (1 - gap_after% / gap_before%), held out
  std::vector<std::pair<std::string, double>> params;  ///< its fitted parameters (nominal ones too)
  Signature signature;           ///< of the residual before it was added
};

struct Diagnosis {
  std::vector<std::string> train_runs, heldout_runs;
  OutputMap map = OutputMap::kAngles;
  Gap heldout_uncalibrated;  ///< the simulator as given
  Gap gap_before;            ///< held out, after calibrating the nominal physics
  Gap train_before;
  Gap noise;                 ///< noise floor of the held-out data, same measure
  std::vector<std::pair<std::string, double>> nominal_params;
  std::vector<CandidateResult> ranking;  ///< round 1, best first
  std::vector<CandidateResult> later_rounds;
  std::vector<std::string> selected;
  /// Held-out gap after each kept effect, its calibration polished.
  std::vector<std::pair<std::string, Gap>> steps;
  Gap gap_after;                 ///< held out, with the selected effects
  std::vector<std::pair<std::string, double>> final_params;
  Breakdown where, where_after;
  std::string verdict;           ///< in words
  sim::SimConfig calibrated, final_config;
  // Traces for the report: the first held-out run.
  Eigen::MatrixXd trace_real, trace_before, trace_after;
  double trace_dt = 0.0;
  double elapsed_s = 0.0;
};

/// `runs` with two or more entries: split by run (the last third, at least
/// one, held out); one run: split by time. Throws std::invalid_argument on
/// unusable input (no runs, no candidates, an unknown candidate).
Diagnosis runDiagnosis(const sim::SimConfig& simulator, const std::vector<RunData>& runs, const DiagnoseOptions& options);

std::string toJson(const Diagnosis& d);
/// One self-contained page: verdict, gap map, traces, shrinkage per effect, tables.
std::string reportHtml(const Diagnosis& d);

}  // namespace plsa::diagnose
