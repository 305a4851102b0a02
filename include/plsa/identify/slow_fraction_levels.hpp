// Tied slow fractions chosen by simulated level. The least squares on output
// increments hardly sees a slow mode: over a sample its increment is small
// beside the fast response's and the noise, so the fractions it fits are
// poorly determined, while the simulated output is where creep shows. For
// given fast coefficients the simulated level is affine in the fractions,
//   y_sim = l + s(alpha) + sum_m delta_m s_m,
// s_m the level simulated with each region's coefficients through K_m alone,
// so a step of the fractions on the training records' levels is a small
// least squares beside one pass of simulation (docs/identification.md,
// 'Slow poles').
#pragma once

#include <Eigen/Dense>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/identify/slow_mode_tie.hpp"

namespace plsa::identify {

struct LevelFractionStep {
  SlowFractions alpha;  ///< the fractions that fit the simulated level best, the fast coefficients held
  double misfit = 0.0;  ///< weighted squared level error at the fractions given, each output's level fitted
};

/// From the fractions `alpha` and the fast coefficients `tie.fast` solved at
/// them: the model `structure` (with the slow poles) simulated on the
/// records, and the fractions' least-squares step on its level. One set of
/// fractions for every output when `shared`.
LevelFractionStep levelFractionStep(const TiedSlowMode& tie, const DioPwlObfModel& structure,
                                    const SlowFractions& alpha, const LevelRecords& records, bool shared);

}  // namespace plsa::identify
