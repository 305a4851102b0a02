// The diagnosis's calibration starts and budgets (src/diagnose only, not
// installed): where a candidate effect's calibration starts, the nominal
// calibration from data-derived starts, and the budget a candidate gets.
#pragma once

#include <string>
#include <vector>

#include "plsa/diagnose/fill_law_estimate.hpp"
#include "plsa/diagnose/calibration.hpp"
#include "plsa/diagnose/diagnosis.hpp"

namespace plsa::diagnose {

/// A candidate switched on, with its flexible law unless told otherwise.
void enableCandidate(sim::SimConfig& c, const std::string& effect, const DiagnoseOptions& o);

/// A calibration start: the configuration, and the parameters it holds at
/// their values (CalibrationOptions::held).
struct CalibrationStart {
  sim::SimConfig config;
  std::vector<std::string> held;
};

/// Spread points for an effect (the simulator's own values, points across
/// each parameter's range, designed hysteresis points, sensor bias from the
/// residual when the outputs are angles (an affine map's residual is in the
/// outputs' units), the pneumatic lag from `fill` when found); the first is
/// the configuration itself. Of a weighted Prandtl-Ishlinskii hysteresis's
/// points, those with the smooth element alone hold the plays' parameters,
/// and the range points (the plays alone) the smooth element's.
std::vector<CalibrationStart> spreadFor(const sim::SimConfig& c, const std::string& effect,
                                        const std::vector<RunData>& train, const FillLawEstimate& fill, OutputMap map);

/// The screening stage: a short calibration of `evaluations` simulator runs
/// from each spread point, with the simulator's internal step at least
/// `step_s` (0: as configured).
struct Screening {
  int evaluations = 0;
  double step_s = 0.0;
};

/// `c` with its internal step raised to at least `step_s`, and where that
/// raises it, integrated by `integrator`.
sim::SimConfig atLeastStep(sim::SimConfig c, double step_s, const std::string& integrator);

/// `calibrate` with the simulator's internal step at least `step_s` (where
/// coarser, integrated by `o.coarse_integrator`); the result's
/// configuration carries `start`'s step and integrator again (its training
/// gap and output map are the coarser step's).
CalibrationResult calibrateCoarse(const sim::SimConfig& start, double step_s, const std::vector<std::string>& modules,
                                  const std::vector<RunData>& train, const CalibrationOptions& o);

/// A candidate's two calibration starts: neutral (the effect switched on
/// but doing nothing), and the best spread point, after the screening stage
/// when `screen.evaluations` > 0, else by its training gap alone
/// (bestSpreadStart adds the runs it spent to `spent`). The spread point's
/// held parameters join `o.held` (the current model's).
sim::SimConfig neutralStart(sim::SimConfig c, const std::string& effect);
CalibrationStart bestSpreadStart(const sim::SimConfig& c, const std::string& effect,
                                 const std::vector<std::string>& modules, const std::vector<RunData>& train,
                                 const FillLawEstimate& fill, const CalibrationOptions& o, const Screening& screen,
                                 int& spent);

/// The nominal physics calibrated from the simulator as given and the best
/// data-derived starts (`fill`: the chambers' time constant and rate limit
/// from logged pressures, when found), then restarted from the best;
/// `spent`: the runs of every stage.
CalibrationResult calibrateNominal(const sim::SimConfig& simulator, const std::vector<RunData>& train,
                                   const FillLawEstimate& fill, const CalibrationOptions& nominal,
                                   const DiagnoseOptions& o, int& spent);

/// The evaluations the largest candidate's calibration may spend.
int candidateBudget(sim::SimConfig c, const std::vector<std::string>& modules,
                    const std::vector<std::string>& candidates, const CalibrationOptions& o);

}  // namespace plsa::diagnose
