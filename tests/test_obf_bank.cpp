#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>

#include "plsa/obf/obf_bank.hpp"
#include "plsa/testing/alloc_guard.hpp"
#include "support/random_poles.hpp"

using plsa::ObfBank;
using plsa::PoleSet;
using C = std::complex<double>;

namespace {

// Independent closed forms: Takenaka-Malmquist for real poles, Kautz for a
// pair, each multiplied by the inner functions of all earlier sections.
Eigen::VectorXcd closedForm(const PoleSet& poles, C z) {
  Eigen::VectorXcd out(poles.size());
  C inner(1.0, 0.0);
  int i = 0;
  for (const auto& s : poles.sections()) {
    const C xi = s.pole;
    if (!s.is_pair()) {
      out(i++) = std::sqrt(1.0 - std::norm(xi)) / (z - xi) * inner;
      inner *= (1.0 - std::conj(xi) * z) / (z - xi);
    } else {
      const double a2 = std::norm(xi);
      const double b = 2.0 * xi.real() / (1.0 + a2);
      const double c = -a2;
      const C den = (z - xi) * (z - std::conj(xi));
      out(i++) = std::sqrt(1.0 - c * c) * (z - b) / den * inner;
      out(i++) = std::sqrt((1.0 - c * c) * (1.0 - b * b)) / den * inner;
      inner *= (1.0 - std::conj(xi) * z) * (1.0 - xi * z) / den;
    }
  }
  return out;
}

}  // namespace

TEST(ObfBank, GramMatrixOfImpulseResponsesIsIdentity) {
  std::mt19937 rng(7);
  for (int seed = 0; seed < plsa::test::seedCount(); ++seed) {
    const PoleSet poles = plsa::test::randomPoleSet(rng, 1 + seed % 6);
    const ObfBank<> bank(poles);
    const Eigen::MatrixXd h = bank.impulseResponse(4000);
    const Eigen::MatrixXd gram = h.transpose() * h;
    const double err = (gram - Eigen::MatrixXd::Identity(bank.size(), bank.size())).cwiseAbs().maxCoeff();
    EXPECT_LT(err, 1e-9) << "seed " << seed << " with " << bank.size() << " functions";
  }
}

TEST(ObfBank, RealisationMatrixIsOrthogonal) {
  std::mt19937 rng(11);
  for (int seed = 0; seed < plsa::test::seedCount(); ++seed) {
    const ObfBank<> bank(plsa::test::randomPoleSet(rng, 1 + seed % 5, 0.99));
    const int n = bank.size();
    Eigen::MatrixXd R(n + 1, n + 1);
    R << bank.A(), bank.B(), bank.C(), bank.D();
    EXPECT_LT((R.transpose() * R - Eigen::MatrixXd::Identity(n + 1, n + 1)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(ObfBank, TransferMatchesClosedFormAtRandomFrequencies) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> w(0.0, M_PI);
  for (int seed = 0; seed < plsa::test::seedCount(); ++seed) {
    const PoleSet poles = plsa::test::randomPoleSet(rng, 1 + seed % 6, 0.95);
    const ObfBank<> bank(poles);
    for (int f = 0; f < 5; ++f) {
      const C z = std::polar(1.0, w(rng));
      const Eigen::VectorXcd got = bank.transfer(z);
      const Eigen::VectorXcd want = closedForm(poles, z);
      EXPECT_LT((got - want).cwiseAbs().maxCoeff(), 1e-10 * std::max(1.0, want.cwiseAbs().maxCoeff()))
          << "seed " << seed;
    }
  }
}

TEST(ObfBank, InnerFunctionIsAllPass) {
  std::mt19937 rng(5);
  const ObfBank<> bank(plsa::test::randomPoleSet(rng, 4));
  const int n = bank.size();
  for (double w : {0.1, 0.7, 2.0, 3.1}) {
    const C z = std::polar(1.0, w);
    const Eigen::MatrixXcd M = z * Eigen::MatrixXcd::Identity(n, n) - bank.A().cast<C>();
    const C g = (bank.C().cast<C>() * M.partialPivLu().solve(bank.B().cast<C>()))(0) + bank.D();
    EXPECT_NEAR(std::abs(g), 1.0, 1e-12);
  }
}

TEST(ObfBank, FirReducesToPureDelays) {
  const ObfBank<> bank(PoleSet::fir(5));
  const Eigen::MatrixXd h = bank.impulseResponse(8);  // row k = lag k+1
  for (int lag = 1; lag <= 8; ++lag)
    for (int i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(h(lag - 1, i), lag == i + 1 ? 1.0 : 0.0);
}

TEST(ObfBank, LaguerreMatchesTextbookForm) {
  const double a = 0.7;
  const ObfBank<> bank(PoleSet::laguerre(a, 4));
  // First Laguerre function: sqrt(1-a^2) a^(k-1) at lag k.
  const Eigen::MatrixXd h = bank.impulseResponse(30);
  for (int k = 1; k <= 30; ++k) EXPECT_NEAR(h(k - 1, 0), std::sqrt(1 - a * a) * std::pow(a, k - 1), 1e-14);
  // L_i(z) = sqrt(1-a^2)/(z-a) ((1-az)/(z-a))^(i-1).
  for (double w : {0.2, 1.3, 2.9}) {
    const C z = std::polar(1.0, w);
    const Eigen::VectorXcd got = bank.transfer(z);
    for (int i = 0; i < 4; ++i) {
      const C want = std::sqrt(1 - a * a) / (z - a) * std::pow((1.0 - a * z) / (z - a), i);
      EXPECT_LT(std::abs(got(i) - want), 1e-12);
    }
  }
}

TEST(ObfBank, FixedSizeMatchesDynamic) {
  const PoleSet poles({C(0.9, 0), C(0.6, 0.3), C(0.6, -0.3), C(-0.2, 0), C(0.95, 0)});
  ObfBank<5> fixed(poles);
  ObfBank<> dyn(poles);
  std::mt19937 rng(1);
  std::normal_distribution<double> n01;
  for (int k = 0; k < 500; ++k) {
    const double u = n01(rng);
    fixed.step(u);
    dyn.step(u);
  }
  EXPECT_LT((fixed.state() - dyn.state()).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_GT(dyn.state().norm(), 0.1);
}

TEST(ObfBank, FixedSizeRejectsWrongPoleCount) {
  EXPECT_THROW(ObfBank<3>(PoleSet::fir(4)), std::invalid_argument);
  EXPECT_THROW(ObfBank<>{PoleSet()}, std::invalid_argument);
}

TEST(ObfBank, KnownPolesNeedFewFunctions) {
  // G(q) = 0.5/(q-0.9) + 0.3/(q-0.6) + Kautz pair at 0.8+-0.3i.
  const C p(0.8, 0.3);
  const int T = 3000;
  Eigen::VectorXd g(T);
  for (int k = 1; k <= T; ++k)
    g(k - 1) = 0.5 * std::pow(0.9, k - 1) + 0.3 * std::pow(0.6, k - 1) + 2.0 * (0.4 * std::pow(p, k - 1)).real();
  auto residual = [&](const PoleSet& poles) {
    const Eigen::MatrixXd h = ObfBank<>(poles).impulseResponse(T);
    const Eigen::VectorXd c = h.transpose() * g;  // orthonormal: projection
    return (g - h * c).norm() / g.norm();
  };
  const double on_poles = residual(PoleSet({C(0.9, 0), C(0.6, 0), p, std::conj(p)}));
  const double laguerre = residual(PoleSet::laguerre(0.3, 4));
  const double fir = residual(PoleSet::fir(4));
  EXPECT_LT(on_poles, 1e-10);
  EXPECT_GT(laguerre, 0.05);
  EXPECT_GT(fir, 0.1);
}

TEST(ObfBank, StepAllocatesNothing) {
  ObfBank<> dyn(PoleSet::real({0.9, 0.8, 0.7, 0.6, 0.5}));
  ObfBank<5> fixed(PoleSet::real({0.9, 0.8, 0.7, 0.6, 0.5}));
  plsa::testing::AllocGuard guard;
  for (int k = 0; k < 10000; ++k) {
    dyn.step(std::sin(0.01 * k));
    fixed.step(std::cos(0.01 * k));
  }
  EXPECT_EQ(guard.allocations(), 0u);
}
