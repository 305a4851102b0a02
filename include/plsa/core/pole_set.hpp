// A validated set of stable discrete-time poles for an orthonormal basis:
// real poles and complex-conjugate pairs, kept in the order given, each pair
// stored once as one second-order section (its pole with positive imaginary part).
#pragma once

#include <cmath>
#include <complex>
#include <cstddef>
#include <sstream>
#include <vector>

#include "plsa/core/check.hpp"

namespace plsa {

class PoleSet {
 public:
  /// One all-pass section: a real pole (1 state) or a conjugate pair (2 states).
  struct Section {
    std::complex<double> pole;  // for a pair: the member with Im > 0
    bool is_pair() const { return pole.imag() != 0.0; }
    int order() const { return is_pair() ? 2 : 1; }
  };

  /// Imaginary parts at or below this (relative to max(1,|p|)) count as real.
  static constexpr double kRealTolerance = 1e-12;
  /// Two poles are conjugates if they differ by at most this (relative).
  static constexpr double kPairTolerance = 1e-9;

  PoleSet() = default;

  /// Poles in any order; complex poles must come with their conjugates.
  /// Throws std::invalid_argument naming the offending pole otherwise.
  explicit PoleSet(const std::vector<std::complex<double>>& poles) {
    std::vector<bool> used(poles.size(), false);
    for (std::size_t i = 0; i < poles.size(); ++i) {
      if (used[i]) continue;
      const std::complex<double> p = poles[i];
      checkStable(p, i);
      const double scale = std::max(1.0, std::abs(p));
      if (std::abs(p.imag()) <= kRealTolerance * scale) {
        used[i] = true;
        sections_.push_back({std::complex<double>(p.real(), 0.0)});
        continue;
      }
      std::size_t partner = poles.size();
      for (std::size_t j = i + 1; j < poles.size(); ++j) {
        if (!used[j] && std::abs(poles[j] - std::conj(p)) <= kPairTolerance * scale) {
          partner = j;
          break;
        }
      }
      if (partner == poles.size()) {
        std::ostringstream msg;
        msg << "PoleSet: complex pole " << i << " (" << p.real() << (p.imag() < 0 ? "" : "+") << p.imag()
            << "i) has no conjugate partner; complex poles must come in "
            << "conjugate pairs so that the basis stays real";
        throw std::invalid_argument(msg.str());
      }
      used[i] = used[partner] = true;
      sections_.push_back({p.imag() > 0 ? p : std::conj(p)});
    }
  }

  /// Real poles only.
  static PoleSet real(const std::vector<double>& poles) {
    std::vector<std::complex<double>> c(poles.begin(), poles.end());
    return PoleSet(c);
  }
  /// FIR basis: n poles at the origin (B_i = q^-i).
  static PoleSet fir(int n) { return real(std::vector<double>(checkCount(n), 0.0)); }
  /// Laguerre basis: one real pole repeated n times.
  static PoleSet laguerre(double a, int n) { return real(std::vector<double>(checkCount(n), a)); }
  /// Two-parameter Kautz basis: one conjugate pair repeated n_pairs times.
  static PoleSet kautz(std::complex<double> p, int n_pairs) {
    PLSA_CHECK(p.imag() != 0.0, "PoleSet::kautz: the pole must be complex (Im != 0)");
    std::vector<std::complex<double>> c;
    for (int i = 0; i < checkCount(n_pairs); ++i) {
      c.push_back(p);
      c.push_back(std::conj(p));
    }
    return PoleSet(c);
  }
  /// Generalised OBF: a pole block repeated `times` times.
  static PoleSet repeated(const PoleSet& block, int times) {
    PoleSet out;
    for (int r = 0; r < checkCount(times); ++r)
      out.sections_.insert(out.sections_.end(), block.sections_.begin(), block.sections_.end());
    return out;
  }

  const std::vector<Section>& sections() const { return sections_; }
  /// Number of basis functions (= states), counting a pair as two.
  int size() const {
    int n = 0;
    for (const auto& s : sections_) n += s.order();
    return n;
  }
  bool empty() const { return sections_.empty(); }

  /// Every pole, a pair expanded into both members.
  std::vector<std::complex<double>> poles() const {
    std::vector<std::complex<double>> out;
    for (const auto& s : sections_) {
      out.push_back(s.pole);
      if (s.is_pair()) out.push_back(std::conj(s.pole));
    }
    return out;
  }

 private:
  static void checkStable(std::complex<double> p, std::size_t index) {
    if (!std::isfinite(p.real()) || !std::isfinite(p.imag())) {
      std::ostringstream msg;
      msg << "PoleSet: pole " << index << " is not a finite number (" << p.real() << ", " << p.imag() << ")";
      throw std::invalid_argument(msg.str());
    }
    if (std::abs(p) >= 1.0) {
      std::ostringstream msg;
      msg << "PoleSet: pole " << index << " (" << p.real() << (p.imag() < 0 ? "" : "+") << p.imag() << "i) has modulus "
          << std::abs(p) << " >= 1; basis poles must lie strictly inside the unit disk";
      throw std::invalid_argument(msg.str());
    }
  }
  static int checkCount(int n) {
    PLSA_CHECK(n >= 1, "PoleSet: the number of poles must be at least 1");
    return n;
  }

  std::vector<Section> sections_;
};

}  // namespace plsa
