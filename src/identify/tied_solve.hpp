// The coefficient fit's solves on summed terms, shared by the untied
// (coefficient_fit.cpp) and the tied slow-pole fit (tied_solve.cpp).
#pragma once

#include "plsa/identify/coefficient_fit.hpp"

namespace plsa::identify {

/// The solve behind solveCoefficients on summed terms, in the model's
/// coordinates; `joint` for interpolated and input-side structures.
CoefficientFitReport solveGroup(DioPwlObfModel& model, CoefficientSums::Group& total, bool joint,
                                const CoefficientFitOptions& o);

/// One fit for solveTied: the model it solves into (its structure with the
/// slow poles), its summed terms, and its weights over the level records
/// (empty: every sample once).
struct TiedFit {
  DioPwlObfModel& model;
  const CoefficientSums::Group& total;
  const SampleWeights& weights;
};

/// Fits of one structure with the slow poles' coefficients tied
/// (options.slow_mode): fractions on the increments, then, when asked and the
/// records U and Y (model frame) are given, on the simulated level, every fit
/// simulated in the same pass; mapped back onto the models' banks.
std::vector<CoefficientFitReport> solveTied(std::vector<TiedFit> fits, const CoefficientFitOptions& o,
                                            const std::vector<Eigen::MatrixXd>* U,
                                            const std::vector<Eigen::MatrixXd>* Y);

}  // namespace plsa::identify
