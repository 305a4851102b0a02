// The chambers' fill law read off logged pressures alone: the diagnosis's
// data-derived starts for the nominal chamber time constant and for the
// pneumatic lag's calibration (docs/diagnosis.md).
#pragma once

#include <string>
#include <vector>

#include "plsa/diagnose/run_data.hpp"

namespace plsa::diagnose {

/// The chambers' filling as plsa's simulator steps it (power flow law,
/// docs/simulator.md): dp/dt = sign(d) 0.1 (|d| / 0.1)^exponent / (tau
/// exp(per_bar p)), limited to +-max_rate, d the command `delay_s` earlier
/// less the pressure p, tau the fill or the vent time constant by the sign
/// of d. With a supply line (line_time_constant_s > 0) the chamber fills
/// from the line's pressure instead, the line from the command, first-order.
/// The nominal law is exponent 1, per_bar 0, no delay, no line, one tau.
struct FillLaw {
  double fill_time_constant_s = 0.05, vent_time_constant_s = 0.05;
  double exponent = 1.0, pressure_per_bar = 0.0, delay_s = 0.0;
  double max_rate_bar_per_s = 8.0;
  double line_time_constant_s = 0.0;
};

/// Both fits of the logged pressures; `found` is false when the runs log no
/// pressures or have too few samples.
struct FillLawEstimate {
  bool found = false;
  FillLaw nominal;                                  ///< one time constant and the rate limit free
  FillLaw lag;                                      ///< the best of the full fits (fillLawFromPressures)
  double nominal_rms_bar = 0.0, lag_rms_bar = 0.0;  ///< the fits' pressure residuals
  double noise_bar = 0.0;   ///< the logged pressures' white noise (second differences, median-based)
  double spread_bar = 0.0;  ///< the logged pressures' standard deviation
};

/// The mean squared pressure residual of `law` on the runs: each chamber's
/// pressure stepped from its first logged value by the law (explicit steps
/// of at most 5 ms that never overshoot the command), the command before
/// the run (and the line's pressure, with a line) 0 for a run recorded from
/// rest and its first command for a settled one. Runs without pressures
/// are skipped.
double pressureMisfit(const FillLaw& law, const std::vector<RunData>& runs);

/// Fits the nominal law from `start` (its time constant and rate limit),
/// then the full law but the line from that answer and from a
/// pressure-dependent start, and two volumes in series with linear flows
/// from the nominal time constant split 1:2 between them (the best of the
/// three kept; on `threads` threads), by bounded BOBYQA on
/// pressureMisfit over the runs' first minute at 80 Hz (4800 samples in
/// all), at most `evaluations` runs of the law each. A data-derived start,
/// not a calibration: the simulator's other parameters play no part.
FillLawEstimate fillLawFromPressures(const std::vector<RunData>& runs, const FillLaw& start, int evaluations = 120,
                                     int threads = 1);

/// What the pressures say when no fill law fits them: a note for the
/// diagnosis when the best law leaves over twice the pressures' noise (or
/// they have no measurable noise) and over 2% of their spread (a valve's
/// quantisation, a regulator's own loop: what no pneumatic-lag candidate
/// can close); empty otherwise or when nothing was fitted.
std::string unmodelledPneumaticsNote(const FillLawEstimate& estimate);

}  // namespace plsa::diagnose
