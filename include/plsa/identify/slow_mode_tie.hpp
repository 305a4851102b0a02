// Slow modes as creep: for each slow pole p_m a fraction alpha_m of each
// bank's response follows it again through a first-order lag,
//   F(q) B(q) c,   F(q) = 1 + sum_m alpha_m (1 - p_m) / (q - p_m),
// one set of fractions for the whole model (or one per output). F B c is a
// strictly proper rational function of the bank's poles and the p_m, so it
// lies in the span of the bank that carries them besides its own poles: the
// model file and the predictor are those of a bank with more poles, only the
// coefficients are tied, c_slow = (A + sum_m alpha_m K_m) c. In the tip frame
// the lags act alike on both tip components, so what creeps under a held
// input keeps the direction the fast response gave the tip
// (docs/identification.md, 'Slow poles').
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// The fractions of every output: [output](slow pole).
using SlowFractions = std::vector<Eigen::VectorXd>;

/// One output's map from a region's coefficients on the banks without the
/// slow poles (width_fast) to those with them (width_slow):
/// A + sum_m alpha_m K_m.
struct TiedBlock {
  Eigen::MatrixXd A;
  std::vector<Eigen::MatrixXd> K;  ///< [slow pole]
  Eigen::MatrixXd at(const Eigen::VectorXd& alpha) const {
    Eigen::MatrixXd M = A;
    for (std::size_t m = 0; m < K.size(); ++m) M += alpha(static_cast<Eigen::Index>(m)) * K[m];
    return M;
  }
};

/// The model without the slow poles, and each output's tied block.
struct TiedSlowMode {
  DioPwlObfModel fast;            ///< the model's structure, each bank less one copy of each slow pole
  std::vector<TiedBlock> blocks;  ///< [output]
};

/// Throws std::invalid_argument unless every bank of `model` carries every
/// one of `poles` (distinct, real, in (0, 1)) besides at least one pole.
TiedSlowMode tiedSlowMode(const DioPwlObfModel& model, const std::vector<double>& poles);

/// The summed least-squares terms of an input-side model with the slow poles
/// (full symmetric J), in the coordinates of the model without them at the
/// fractions `alpha`.
CoefficientSums::Group reducedGroup(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                    const SlowFractions& alpha);

/// The fractions that fit the blended (all nodes equal) problem best, by
/// alternating least squares over the coefficients and the fractions: one
/// set for every output when `shared`, else one each. `ridge` as the fit's.
/// A start for the full problem's (gaussNewtonFractions).
SlowFractions fitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total, bool shared, double ridge);

/// One Gauss-Newton step of variable projection on the full (per node)
/// problem from the fractions `alpha`, at the coefficients `fast` holds (the
/// model without the slow poles, solved at `alpha`): the fractions' least
/// squares with the coefficients' best response to them projected out.
SlowFractions gaussNewtonFractions(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                   const DioPwlObfModel& fast, const SlowFractions& alpha, bool shared);

/// The data misfit of the tied coefficients at the fractions `alpha`,
/// sum over outputs of c'Jc - 2 c'Jh, where c is each region's coefficients
/// in `fast` (the model without the slow poles) mapped through the tie.
double tiedMisfit(const TiedSlowMode& tie, const CoefficientSums::Group& total, const DioPwlObfModel& fast,
                  const SlowFractions& alpha);

/// Whether a step moved the fractions by less than 1e-7 (relative).
bool slowFractionSettled(const SlowFractions& before, const SlowFractions& after);

}  // namespace plsa::identify
