// The slow pole as creep: a fraction alpha of each bank's response follows
// it again through a first-order lag of the slow pole p,
//   F(q) B(q) c,   F(q) = 1 + alpha (1 - p) / (q - p),
// one alpha for the whole model (or one per output). F B c is a strictly
// proper rational function of the bank's poles and p, so it lies in the span
// of the bank that carries p besides its own poles: the model file and the
// predictor are those of a bank with one more pole, only the coefficients are
// tied, c_slow = (A + alpha K) c. In the tip frame the lag acts alike on both
// tip components, so what creeps under a held input keeps the direction the
// fast response gave the tip (docs/identification.md, 'Slow pole').
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "plsa/identify/coefficient_fit.hpp"
#include "plsa/model/dio_pwl_obf_model.hpp"

namespace plsa::identify {

/// One output's map from a region's coefficients on the banks without the
/// slow pole (width_fast) to those with it (width_slow): A + alpha K.
struct TiedBlock {
  Eigen::MatrixXd A, K;
  Eigen::MatrixXd at(double alpha) const { return A + alpha * K; }
};

/// The model without the slow pole, and each output's tied block.
struct TiedSlowMode {
  DioPwlObfModel fast;            ///< the model's structure, each bank less one copy of the slow pole
  std::vector<TiedBlock> blocks;  ///< [output]
};

/// Throws std::invalid_argument unless every bank of `model` carries `pole`
/// (real, in (0, 1)).
TiedSlowMode tiedSlowMode(const DioPwlObfModel& model, double pole);

/// The summed least-squares terms of an input-side model with the slow pole
/// (full symmetric J), in the coordinates of the model without it at the
/// fractions `alpha` ([output]).
CoefficientSums::Group reducedGroup(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                    const std::vector<double>& alpha);

/// The fractions that fit the blended (all nodes equal) problem best, by
/// alternating least squares over the coefficients and the fractions: one
/// for every output when `shared`, else one each. `ridge` as the fit's. A
/// start for the full problem's (refitSlowFraction).
std::vector<double> fitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total, bool shared,
                                    double ridge);

/// One alternating step on the full (per node) problem: the fractions that
/// fit best given the coefficients `fast` holds (the model without the slow
/// pole, as solved at the previous fractions).
std::vector<double> refitSlowFraction(const TiedSlowMode& tie, const CoefficientSums::Group& total,
                                      const DioPwlObfModel& fast, bool shared);

/// Whether an alternating step moved the fractions by less than 1e-7 (relative).
bool slowFractionSettled(const std::vector<double>& before, const std::vector<double>& after);

}  // namespace plsa::identify
