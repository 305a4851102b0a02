// A bank of orthonormal basis filters B_1(q)..B_n(q) driven by one input:
// the cascade of all-pass sections of a PoleSet, run as one state-space
// x+ = A x + B u whose states are the basis outputs (method notes, "OBF").
#pragma once

#include <complex>
#include <string>

#include <Eigen/Dense>

#include "plsa/core/check.hpp"
#include "plsa/core/pole_set.hpp"
#include "plsa/obf/allpass_section.hpp"

namespace plsa {

/// N = number of basis functions, fixed at compile time, or Eigen::Dynamic.
/// Construction validates and allocates; step() never allocates or throws.
/// Note the basis is strictly proper: state() at time k depends on inputs up
/// to k-1, so step(u_k) moves the state from x_k to x_{k+1}.
template <int N = Eigen::Dynamic>
class ObfBank {
 public:
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  using RowVector = Eigen::Matrix<double, 1, N>;

  ObfBank() = default;

  explicit ObfBank(const PoleSet& poles) : poles_(poles) {
    PLSA_CHECK(!poles.empty(), "ObfBank: the pole set is empty");
    const int n = poles.size();
    if constexpr (N != Eigen::Dynamic) {
      PLSA_CHECK(n == N,
                 "ObfBank<" + std::to_string(N) + ">: the pole set has " + std::to_string(n) + " basis functions");
    }
    A_.setZero(n, n);
    B_.setZero(n);
    C_.setZero(n);
    x_.setZero(n);
    tmp_.setZero(n);
    // The input of the current section is w = C_ x + D_ u.
    D_ = 1.0;
    int offset = 0;
    for (const auto& sec : poles.sections()) {
      const AllpassSection s = sec.is_pair() ? AllpassSection::pair(sec.pole) : AllpassSection::real(sec.pole.real());
      const int m = s.order;
      A_.block(offset, 0, m, n) += s.B.head(m) * C_;
      A_.block(offset, offset, m, m) += s.A.topLeftCorner(m, m);
      B_.segment(offset, m) = s.B.head(m) * D_;
      C_ *= s.D;
      C_.segment(offset, m) += s.C.head(m);
      D_ *= s.D;
      offset += m;
    }
  }

  /// Advance one sample with input u. Allocation-free, noexcept.
  void step(double u) noexcept {
    tmp_.noalias() = A_ * x_;
    x_ = tmp_ + B_ * u;
  }

  void reset() noexcept { x_.setZero(); }
  int size() const noexcept { return static_cast<int>(x_.size()); }
  const Vector& state() const noexcept { return x_; }
  Vector& state() noexcept { return x_; }
  const PoleSet& poles() const noexcept { return poles_; }

  /// State-space of the whole cascade; (C, D) realise the inner function G_b.
  const Matrix& A() const noexcept { return A_; }
  const Vector& B() const noexcept { return B_; }
  const RowVector& C() const noexcept { return C_; }
  double D() const noexcept { return D_; }

  /// B_1(z)..B_n(z) at a point z of the complex plane (set-up and analysis use).
  Eigen::VectorXcd transfer(std::complex<double> z) const {
    const int n = size();
    Eigen::MatrixXcd M = z * Eigen::MatrixXcd::Identity(n, n) - A_.template cast<std::complex<double>>();
    return M.partialPivLu().solve(B_.template cast<std::complex<double>>().eval());
  }

  /// Impulse responses of the basis functions, one column per function.
  Eigen::MatrixXd impulseResponse(int length) const {
    ObfBank copy(*this);
    copy.reset();
    Eigen::MatrixXd h(length, size());
    for (int k = 0; k < length; ++k) {
      copy.step(k == 0 ? 1.0 : 0.0);
      h.row(k) = copy.state().transpose();
    }
    return h;
  }

 private:
  PoleSet poles_;
  Matrix A_;
  Vector B_;
  RowVector C_;
  double D_ = 1.0;
  Vector x_;
  Vector tmp_;
};

}  // namespace plsa
