#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "plsa/obf/decay_rate.hpp"
#include "plsa/obf/obf_bank.hpp"
#include "support/random_poles.hpp"

using plsa::PoleSet;
using C = std::complex<double>;

// Brute force: expand a first-order system 1/(q-p) in a GOBF that repeats a
// pole block R times, by projecting impulse responses, and measure how fast
// the coefficients of successive blocks shrink. That ratio is rho.
TEST(DecayRate, MatchesCoefficientDecayOfRepeatedBlocks) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> uni(-0.85, 0.85);
  for (int seed = 0; seed < plsa::test::seedCount(); ++seed) {
    const int nb = 1 + seed % 3;
    std::vector<double> block_poles;
    for (int i = 0; i < nb; ++i) block_poles.push_back(uni(rng));
    const PoleSet block = PoleSet::real(block_poles);
    const double p = uni(rng);
    const int reps = 4;
    const int T = 4000;
    const Eigen::MatrixXd h = plsa::ObfBank<>(PoleSet::repeated(block, reps)).impulseResponse(T);
    Eigen::VectorXd g(T);
    for (int k = 1; k <= T; ++k) g(k - 1) = std::pow(p, k - 1);
    const Eigen::VectorXd c = h.transpose() * g;
    const double rho = plsa::decayRate(block, {C(p, 0)});
    for (int r = 0; r + 1 < reps; ++r) {
      const double now = c.segment(r * nb, nb).norm();
      const double next = c.segment((r + 1) * nb, nb).norm();
      if (now < 1e-9) continue;  // p sits on a basis pole: nothing left to decay
      EXPECT_NEAR(next / now, rho, 1e-6) << "seed " << seed << " block " << r;
    }
  }
}

TEST(DecayRate, ZeroWhenBasisSitsOnTruePolesAndWorstCaseOtherwise) {
  const PoleSet basis = PoleSet::real({0.9, 0.5});
  EXPECT_NEAR(plsa::decayRate(basis, {C(0.9, 0), C(0.5, 0)}), 0.0, 1e-15);
  const double far = plsa::decayRate(basis, {C(-0.5, 0)});
  const double both = plsa::decayRate(basis, {C(0.9, 0), C(-0.5, 0)});
  EXPECT_DOUBLE_EQ(both, far);
  EXPECT_GT(far, 0.5);
}

TEST(DecayRate, ComplexPairsUseBothMembers) {
  const C p(0.6, 0.3);
  EXPECT_NEAR(plsa::decayRate(PoleSet({p, std::conj(p)}), {p, std::conj(p)}), 0.0, 1e-15);
  const double d = plsa::poleDistance(p, std::conj(p)) * plsa::poleDistance(p, p);
  EXPECT_EQ(d, 0.0);
}

TEST(DecayRate, RejectsEmptyInputs) {
  EXPECT_THROW(plsa::decayRate(PoleSet(), {C(0.5, 0)}), std::invalid_argument);
  EXPECT_THROW(plsa::decayRate(PoleSet::fir(1), {}), std::invalid_argument);
}
