#include "plsa/identify/local_fit.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "plsa/core/check.hpp"

namespace plsa::identify {

LocalFit fitLocalModel(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double u0, double y0, int order,
                       double max_std_error, double min_snr) {
  PLSA_CHECK(order >= 1 && order <= 6, "fitLocalModel: order must be 1 to 6");
  PLSA_CHECK(u.size() == y.size(), "fitLocalModel: u and y lengths differ");
  LocalFit fit;
  const Eigen::Index T = y.size();
  if (T < 4 * order + 4) {
    fit.reason = "segment too short (" + std::to_string(T) + " samples)";
    return fit;
  }
  // Regressors from the sample before the step (de-offset: both start at 0).
  Eigen::VectorXd ud(T + order), yd(T + order);
  ud.head(order).setZero();
  yd.head(order).setZero();
  ud.tail(T) = u.array() - u0;
  yd.tail(T) = y.array() - y0;
  const Eigen::Index rows = T;
  Eigen::MatrixXd phi(rows, 2 * order);
  Eigen::VectorXd target(rows);
  for (Eigen::Index k = 0; k < rows; ++k) {
    const Eigen::Index t = k + order;
    for (int i = 1; i <= order; ++i) {
      phi(k, i - 1) = yd(t - i);
      phi(k, order + i - 1) = ud(t - i);
    }
    target(k) = yd(t);
  }
  // Samples before the step would be all zeros; the first row already sees u.
  const Eigen::MatrixXd gram = phi.transpose() * phi;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(gram);
  const Eigen::VectorXd theta = ldlt.solve(phi.transpose() * target);
  const Eigen::VectorXd resid = target - phi * theta;
  const double sigma2 = resid.squaredNorm() / std::max<Eigen::Index>(1, rows - 2 * order);
  const Eigen::MatrixXd cov = sigma2 * ldlt.solve(Eigen::MatrixXd::Identity(2 * order, 2 * order));
  fit.pole_std_error = std::sqrt(cov.diagonal().head(order).maxCoeff());
  const double amplitude = yd.tail(T).cwiseAbs().maxCoeff();
  fit.snr = amplitude / std::max(std::sqrt(sigma2), 1e-300);
  // Poles: roots of z^n - a1 z^{n-1} - ... - an (companion matrix).
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(order, order);
  comp.row(0) = theta.head(order).transpose();
  if (order > 1) comp.block(1, 0, order - 1, order - 1).setIdentity();
  const Eigen::VectorXcd ev = comp.eigenvalues();
  for (Eigen::Index i = 0; i < ev.size(); ++i) fit.poles.push_back(ev(i));
  const double den = 1.0 - theta.head(order).sum();
  fit.gain = std::abs(den) > 1e-12 ? theta.tail(order).sum() / den : INFINITY;

  std::ostringstream why;
  std::vector<std::complex<double>> kept;
  for (const auto& p : fit.poles) {
    if (!std::isfinite(p.real()) || std::abs(p) >= 1.0) {
      why << "unstable pole " << p.real() << (p.imag() >= 0 ? "+" : "") << p.imag() << "i; ";
    } else if (p.real() < 0.0) {
      // Equation-error fits of order > 1 put a spare pole on the noise; it is
      // dropped there (and noted), but a first-order fit that lands here is wrong.
      if (order == 1)
        why << "negative real pole " << p.real() << " (alternating, not a physical step response); ";
      else
        fit.dropped.push_back(p);
    } else {
      kept.push_back(p);
    }
  }
  fit.poles = kept;
  if (fit.poles.empty() && why.str().empty()) why << "no physical pole left; ";
  // With order > 1 the AR coefficients are correlated, so their standard
  // errors say little about the poles; the SNR test still applies.
  if (order == 1 && fit.pole_std_error > max_std_error)
    why << "pole badly determined (std error " << fit.pole_std_error << "); ";
  if (fit.snr < min_snr) why << "response too small for the noise (SNR " << fit.snr << "); ";
  fit.reason = why.str();
  if (!fit.reason.empty()) fit.reason.resize(fit.reason.size() - 2);
  fit.usable = fit.reason.empty();
  return fit;
}

}  // namespace plsa::identify
