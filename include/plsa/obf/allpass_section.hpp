// State-space realisations of the first- and second-order all-pass sections
// whose cascade forms a Takenaka-Malmquist / Kautz orthonormal basis. Each
// realisation matrix [A B; C D] is orthogonal, so the states are orthonormal.
#pragma once

#include <cmath>
#include <complex>

#include <Eigen/Dense>

namespace plsa {

/// Realisation (A, B, C, D) of one all-pass section of order 1 or 2.
/// States are basis outputs; the section's output feeds the next section.
struct AllpassSection {
  int order = 1;
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d B = Eigen::Vector2d::Zero();
  Eigen::RowVector2d C = Eigen::RowVector2d::Zero();
  double D = 0.0;

  /// Real pole a: s+ = a s + sqrt(1-a^2) w, w_out = sqrt(1-a^2) s - a w
  /// (method notes; the state's transfer is sqrt(1-a^2)/(q-a)).
  static AllpassSection real(double a) {
    AllpassSection s;
    const double k = std::sqrt(1.0 - a * a);
    s.order = 1;
    s.A(0, 0) = a;
    s.B(0) = k;
    s.C(0) = k;
    s.D = -a;
    return s;
  }

  /// Conjugate pair (p, conj p): states are the Kautz functions
  ///   psi1 = sqrt(1-c^2) (q - b) / den,  psi2 = sqrt((1-c^2)(1-b^2)) / den,
  /// den = q^2 + a1 q + a2, a1 = -2 Re p, a2 = |p|^2, b = -a1/(1+a2), c = -a2,
  /// and the output is the all-pass (a2 q^2 + a1 q + 1) / den.
  static AllpassSection pair(std::complex<double> p) {
    const double a1 = -2.0 * p.real();
    const double a2 = std::norm(p);
    const double b = -a1 / (1.0 + a2);
    const double k1 = std::sqrt(1.0 - a2 * a2);
    const double k2 = std::sqrt((1.0 - a2 * a2) * (1.0 - b * b));
    // Controllable canonical form r = [W/den, qW/den], then x = M r.
    Eigen::Matrix2d Ar;
    Ar << 0.0, 1.0, -a2, -a1;
    const Eigen::Vector2d Br(0.0, 1.0);
    const Eigen::RowVector2d Cr(1.0 - a2 * a2, a1 * (1.0 - a2));
    Eigen::Matrix2d M;
    M << -k1 * b, k1, k2, 0.0;
    const Eigen::Matrix2d Minv = M.inverse();
    AllpassSection s;
    s.order = 2;
    s.A = M * Ar * Minv;
    s.B = M * Br;
    s.C = Cr * Minv;
    s.D = a2;
    return s;
  }
};

}  // namespace plsa
