// The coefficient fit's solves on summed terms, shared by the untied
// (coefficient_fit.cpp) and the tied slow-pole fit (tied_solve.cpp).
#pragma once

#include "plsa/identify/coefficient_fit.hpp"

namespace plsa::identify {

/// The solve behind solveCoefficients on summed terms, in the model's
/// coordinates; `joint` for interpolated and input-side structures.
CoefficientFitReport solveGroup(DioPwlObfModel& model, CoefficientSums::Group& total, bool joint,
                                const CoefficientFitOptions& o);

/// The fit with the slow poles' coefficients tied (options.slow_mode):
/// fractions on the increments, then, when asked and `levels` is given, on
/// the simulated level; mapped back onto the model's banks.
CoefficientFitReport solveTied(DioPwlObfModel& model, const CoefficientSums::Group& total,
                               const CoefficientFitOptions& o, const LevelRecords* levels);

}  // namespace plsa::identify
