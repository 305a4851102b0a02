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

/// One fit's part in levelFractionSteps: its tie (tie.fast solved at
/// `alpha`), its weights over the records (empty: every sample once), and
/// whether the step is wanted or the misfit alone (the misfit needs the model
/// at the fractions simulated, the step one more model per slow pole).
struct LevelFractionQuery {
  const TiedSlowMode& tie;
  SlowFractions alpha;
  const SampleWeights& weights;
  bool step = true;
};

/// levelFractionStep for several fits of the one structure on the same
/// records, U and Y (model frame), as cross-validation's folds are: every
/// fit's models simulated in one pass, so the regressors are made once.
std::vector<LevelFractionStep> levelFractionSteps(const DioPwlObfModel& structure,
                                                  const std::vector<LevelFractionQuery>& queries,
                                                  const std::vector<Eigen::MatrixXd>& U,
                                                  const std::vector<Eigen::MatrixXd>& Y, bool shared);

}  // namespace plsa::identify
