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
#include "plsa/diagnose/identified_reference.hpp"
#include "plsa/diagnose/run_checks.hpp"
#include "plsa/diagnose/run_data.hpp"
#include "plsa/sim/sim_config.hpp"

namespace plsa::diagnose {

struct DiagnoseOptions {
  CalibrationOptions calibration;
  int nominal_evaluations = 300;  ///< the nominal fit gets more: it is the baseline everything is judged against
  double heldout_fraction = 0.3;  ///< with a single run: its last part is held out
  double margin = 1.0;  ///< keep an effect only if it shrinks the held-out gap by more than margin x noise floor
  /// ...and by at least this share of the gap (after re-calibrating without
  /// it): form mismatch leaves a structured residual that any added freedom
  /// trims by a few percent, on held-out data too.
  double min_relative = 0.15;
  /// The verdict says "uncertain" when the runner-up reaches more than
  /// 1 - this share of the best's drop over re-calibration.
  double uncertain_margin = 0.25;
  /// ...and "qualified" when the gap left is above this many noise floors.
  double qualified_noise_multiple = 3.0;
  /// Identify a DIO-PWL OBF model on the training runs as the reference
  /// for what the data allow (IdentifiedReference).
  bool identified_reference = true;
  /// The screening stage (first round): a short calibration (this many
  /// simulator runs) from each spread point of a candidate; the best
  /// becomes its second start. The re-calibration bar gets the same runs.
  /// Later rounds, and 0, rank the spread points by their gap alone.
  /// Forty runs were barely BOBYQA's first model of an 11-parameter
  /// candidate; a Bouc-Wen loop's basin was found from 120.
  int screen_evaluations = 120;
  /// The simulator's internal step in the screening stage, where it is
  /// coarser than the configured one (0: the configured step), integrated
  /// by calibration.coarse_integrator: it only ranks the starts, and a 4 ms
  /// step moves a training gap by under 0.1 point while running about four
  /// times fewer steps.
  double screen_step_s = 0.004;
  /// The candidates', the bar's and the polish's calibrations run at this
  /// internal step, or at half of it, when accuracy allows: the coarsest of
  /// the two that, on the calibrated nominal physics, moves the training gap
  /// by at most `coarse_step_tolerance` noise floors (neither: the
  /// configured step; 0: always the configured step), integrated by
  /// calibration.coarse_integrator. A run's step is a whole number a sample
  /// (the nearest). Every gap reported and compared is measured at the
  /// configured step and integrator. 10 ms (one 12.5 ms step a sample at
  /// 80 Hz) with the exponential integrator moved the calibrated training
  /// gap by 0.001-0.024 points on bench/diagnose_cost.py's eight cases
  /// (Euler at 4 ms: up to 0.21) and took x0.64-0.87 of the time, but made
  /// the default it kept a spurious pneumatic lag in one of the three
  /// own-laws cases of Cli.DiagnoseSelfcheckMeetsItsTargetsOnASmallSet
  /// (docs/diagnosis.md): an option, not yet the default.
  double calibration_step_s = 0.004;
  double coarse_step_tolerance = 0.1;
  int max_selected = 3;
  /// Later rounds calibrate a candidate whose round-1 calibration ended no
  /// lower than round 1's bar (re-calibration with nothing added) from the
  /// one start that did best for it in round 1 (false), or from both (true).
  bool both_starts_in_later_rounds = false;
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
  std::string formulation;  ///< the law it was calibrated with
  int round = 1;            ///< forward-selection round it was tried in
  Gap heldout_before, heldout_after, train_after;
  double shrink_percent = 0.0;                         ///< 100 (1 - gap_after% / gap_before%), held out
  std::vector<std::pair<std::string, double>> params;  ///< its fitted parameters (nominal ones too)
  /// Those of `params` its calibration held at their start values: a start
  /// from one part of the effect's family (the weighted Prandtl-Ishlinskii
  /// hysteresis's plays or smooth element alone) holds the other part, and
  /// the model it was kept in holds it in later rounds too.
  std::vector<std::string> held;
  /// How its calibration went: the starts tried (neutral, then the best
  /// after the screening stage of the configured values, spread points and,
  /// for sensor bias, the residual's offset and drift), the simulator runs
  /// spent over all of them (screening included), and the training gap each
  /// start ended at (%).
  /// In a later round a candidate that gained nothing in round 1 has one
  /// start, the one that did best for it there
  /// (DiagnoseOptions::both_starts_in_later_rounds).
  int starts = 0, evaluations = 0;
  std::vector<double> train_gap_per_start;
  int best_start = 0;   ///< the start whose calibration was kept: 0 neutral, 1 the best spread point
  Signature signature;  ///< of the residual before it was added
};

struct Diagnosis {
  std::vector<std::string> train_runs, heldout_runs;
  OutputMap map = OutputMap::kAngles;
  Gap heldout_uncalibrated;  ///< the simulator as given
  Gap gap_before;            ///< held out, after calibrating the nominal physics
  Gap train_before;
  Gap noise;                      ///< noise floor of the held-out data, same measure
  IdentifiedReference reference;  ///< what an identified model reaches on the same split
  std::vector<std::pair<std::string, double>> nominal_params;
  int nominal_evaluations = 0;         ///< simulator runs the nominal calibration spent (grid and every start)
  double calibration_step_s = 0.0;     ///< the internal step the candidates were calibrated at
  std::string calibration_integrator;  ///< and the simulator's integrator there (sim::SimConfig::integrator)
  /// The coarser steps tried for the calibrations, coarsest first, and how
  /// far each moved the calibrated nominal physics' training gap (points).
  std::vector<std::pair<double, double>> calibration_step_trials;
  std::vector<CandidateResult> ranking;  ///< round 1, best first
  std::vector<CandidateResult> later_rounds;
  std::vector<std::string> selected;
  /// Each kept effect, in order: its held-out gap as its round chose it,
  /// and after its calibration was polished on the training runs (the next
  /// round's baseline). A polish that raises the held-out gap by more than
  /// a candidate's margin is noted (notes). `heldout_final`: the model as
  /// the diagnosis leaves it: for the last kept effect, when the selection
  /// stopped in a later round and re-calibrating the kept model with
  /// nothing added (the bar, a candidate's budget) lowered its training
  /// gap, that re-calibration's; else the polished one.
  struct KeptStep {
    std::string effect;
    Gap heldout_chosen;
    Gap heldout;
    Gap heldout_final;
  };
  std::vector<KeptStep> steps;
  Gap gap_after;  ///< held out, with the selected effects
  std::vector<std::pair<std::string, double>> final_params;
  Breakdown where, where_after;
  std::string verdict;  ///< in words
  /// What looks wrong in the input or the search, in words (also logged):
  /// the simulator as given bending ten times as far as the measured angles
  /// or a tenth as far (units: radians for degrees, --input-scale), runs at
  /// different sample rates, a kept effect whose polish (or the kept
  /// model's re-calibration when the selection stopped) raised its held-out
  /// gap by more than a candidate's margin.
  std::vector<std::string> notes;
  /// How firmly the evidence backs the first kept effect (round 1):
  /// "confident", "uncertain" (the runner-up comes within uncertain_margin of
  /// the best's drop over re-calibration, so the data do not separate the
  /// two) or "qualified" (a confident pick whose calibration ends far above
  /// the noise floor: the named effect explains part of the gap, the rest is
  /// something no candidate models). "none" when nothing was kept.
  std::string confidence = "none";
  std::string runner_up;  ///< round 1's second-best candidate
  /// Round 1: the best's drop in squared held-out gap over re-calibration
  /// with nothing added, as a share of that bar (0..1), and the share of
  /// that drop the runner-up does not reach (0: a tie, 1: it gains nothing).
  double margin_over_recalibration = 0.0, margin_over_runner_up = 0.0;
  Gap recalibrated_round1;  ///< round 1's bar: re-calibration with nothing added, the candidates' budget
  sim::SimConfig calibrated, final_config;
  // Traces for the report: the first held-out run.
  Eigen::MatrixXd trace_real, trace_before, trace_after;
  double trace_dt = 0.0;
  double elapsed_s = 0.0;
};

/// `runs` with two or more entries: split by run (the last third, at least
/// one, held out); one run: split by time. A simulator with every effect
/// already on is calibrated and its gap reported, with nothing to try.
/// Throws std::invalid_argument on unusable input (no runs, max_selected
/// under 1, an unknown candidate or one named twice, one already switched
/// on, the same run twice, training commands that drive nothing:
/// constant on runs replayed settled, all at one level; less data than
/// kMinTrainingSeconds / kMinHeldOutSeconds: run_checks.hpp), naming the
/// runs or effect.
Diagnosis runDiagnosis(const sim::SimConfig& simulator, const std::vector<RunData>& runs,
                       const DiagnoseOptions& options);

std::string toJson(const Diagnosis& d);
/// One self-contained page: verdict, gap map, traces, shrinkage per effect, tables.
std::string reportHtml(const Diagnosis& d);
/// Every series the report plots, as CSV text by file name: trace.csv (the
/// first held-out run: real, calibrated sim, sim with the selected
/// effects), gap_map.csv (per chamber-band cell, RMS before and after) and
/// shrink.csv (round-1 candidates). The report links to them by these names.
std::vector<std::pair<std::string, std::string>> reportSeriesCsv(const Diagnosis& d);

/// The files a diagnosis writes into `dir` (made if missing), each
/// atomically: diagnosis.json, report.html with the CSVs it plots, and
/// calibrated_sim.json.
inline const char* const kDiagnosisFiles[] = {"diagnosis.json", "report.html", "calibrated_sim.json",
                                              "trace.csv",      "gap_map.csv", "shrink.csv"};
void writeDiagnosisFolder(const Diagnosis& d, const std::string& dir);

}  // namespace plsa::diagnose
