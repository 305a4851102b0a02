// Seeded random pole sets for property tests; the seed count comes from
// PLSA_TEST_SEEDS (default 20) so bulk runs can go wider.
#pragma once

#include <complex>
#include <cstdlib>
#include <random>
#include <vector>

#include "plsa/core/pole_set.hpp"

namespace plsa::test {

inline int seedCount() {
  const char* env = std::getenv("PLSA_TEST_SEEDS");
  const int n = env ? std::atoi(env) : 0;
  return n > 0 ? n : 20;
}

/// Random real poles and conjugate pairs with modulus below max_modulus.
inline PoleSet randomPoleSet(std::mt19937& rng, int sections, double max_modulus = 0.9, double pair_probability = 0.4) {
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::vector<std::complex<double>> poles;
  for (int s = 0; s < sections; ++s) {
    const double r = max_modulus * std::sqrt(uni(rng));
    if (uni(rng) < pair_probability) {
      const double angle = 0.05 + 3.0 * uni(rng);
      const auto p = std::polar(r, angle);
      poles.push_back(p);
      poles.push_back(std::conj(p));
    } else {
      poles.emplace_back(uni(rng) < 0.5 ? r : -r, 0.0);
    }
  }
  return PoleSet(poles);
}

}  // namespace plsa::test
