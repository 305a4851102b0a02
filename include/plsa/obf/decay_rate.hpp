// The decay rate rho of an OBF expansion: how fast the coefficients of a
// system with poles `true_poles` shrink in a basis built on `basis` (method
// notes: rho = max_p prod_i |(p - xi_i) / (1 - conj(xi_i) p)|; lower is better).
#pragma once

#include <algorithm>
#include <cmath>
#include <complex>
#include <vector>

#include "plsa/core/check.hpp"
#include "plsa/core/pole_set.hpp"

namespace plsa {

/// Kolmogorov distance of one pole p to one basis pole xi (the 1-width inner function).
/// |a / b| as sqrt(|a|^2 / |b|^2): no complex division (libgcc's guards
/// infinities and NaN at a cost that shows when identifying long logs);
/// inside the unit disc neither square can overflow or underflow to harm.
inline double poleDistance(std::complex<double> p, std::complex<double> xi) {
  return std::sqrt(std::norm(p - xi) / std::norm(1.0 - std::conj(xi) * p));
}

/// rho over basis poles given as a plain list (pairs expanded), e.g. cluster centres.
inline double decayRate(const std::vector<std::complex<double>>& xi,
                        const std::vector<std::complex<double>>& true_poles) {
  PLSA_CHECK(!xi.empty(), "decayRate: the basis pole set is empty");
  PLSA_CHECK(!true_poles.empty(), "decayRate: no true poles given");
  double rho = 0.0;
  for (const auto& p : true_poles) {
    double prod = 1.0;
    for (const auto& x : xi) prod *= poleDistance(p, x);
    rho = std::max(rho, prod);
  }
  return rho;
}

/// rho(basis, true poles). Throws if either set is empty.
inline double decayRate(const PoleSet& basis, const std::vector<std::complex<double>>& true_poles) {
  return decayRate(basis.poles(), true_poles);
}

}  // namespace plsa
