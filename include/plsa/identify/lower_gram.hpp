// The Gram matrix of a tile of regressors, the coefficient fit's inner
// product: G = P' P, lower triangle only. On a processor with AVX2 and FMA a
// register-blocked kernel (four columns by two, four rows a step; 2-3x
// Eigen's SSE2 product in a build for any x86-64); elsewhere Eigen's
// rankUpdate. The two differ by rounding in the order of the sums.
#pragma once

#include <Eigen/Dense>

namespace plsa::identify {

/// gram (resized to p.cols() squared): its lower triangle, diagonal included,
/// set to p' p, and its strict upper triangle to zero.
void lowerGram(const Eigen::Ref<const Eigen::MatrixXd>& p, Eigen::MatrixXd& gram);

}  // namespace plsa::identify
