#include "plsa/identify/local_fit.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "plsa/core/check.hpp"

namespace plsa::identify {

namespace {

// The segment's ARX(order, order) equation-error fit from the sample before
// the step (de-offset: both start at 0), with its parameters' covariance.
struct ArxFit {
  Eigen::VectorXd theta;  ///< a1..an, then b1..bn
  Eigen::MatrixXd covariance;
  double sigma2 = 0.0;     ///< residual variance
  double amplitude = 0.0;  ///< largest |y - y0|
};

ArxFit fitSegmentArx(const Eigen::VectorXd& u, const Eigen::VectorXd& y, double u0, double y0, int order) {
  const Eigen::Index T = y.size();
  Eigen::VectorXd ud(T + order), yd(T + order);
  ud.head(order).setZero();
  yd.head(order).setZero();
  ud.tail(T) = u.array() - u0;
  yd.tail(T) = y.array() - y0;
  Eigen::MatrixXd phi(T, 2 * order);
  Eigen::VectorXd target(T);
  for (Eigen::Index k = 0; k < T; ++k) {
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
  ArxFit f;
  f.theta = ldlt.solve(phi.transpose() * target);
  const Eigen::VectorXd resid = target - phi * f.theta;
  f.sigma2 = resid.squaredNorm() / std::max<Eigen::Index>(1, T - 2 * order);
  f.covariance = f.sigma2 * ldlt.solve(Eigen::MatrixXd::Identity(2 * order, 2 * order));
  f.amplitude = yd.tail(T).cwiseAbs().maxCoeff();
  return f;
}

// Poles: roots of z^n - a1 z^{n-1} - ... - an (companion matrix).
std::vector<std::complex<double>> arxPoles(const Eigen::VectorXd& theta, int order) {
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(order, order);
  comp.row(0) = theta.head(order).transpose();
  if (order > 1) comp.block(1, 0, order - 1, order - 1).setIdentity();
  const Eigen::VectorXcd ev = comp.eigenvalues();
  return {ev.data(), ev.data() + ev.size()};
}

// Keeps the physical poles and says why the fit is unusable, if it is.
void judgeFit(LocalFit& fit, int order, double max_std_error, double min_snr) {
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
  const bool physical = why.str().empty();
  // With order > 1 the AR coefficients are correlated, so their standard
  // errors say little about the poles; the SNR test still applies.
  if (order == 1 && fit.pole_std_error > max_std_error)
    why << "pole badly determined (std error " << fit.pole_std_error << "); ";
  if (fit.snr < min_snr) why << "response too small for the noise (SNR " << fit.snr << "); ";
  fit.reason = why.str();
  if (!fit.reason.empty()) fit.reason.resize(fit.reason.size() - 2);
  fit.usable = fit.reason.empty();
  fit.uncertain = !fit.usable && physical;
}

}  // namespace

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
  const ArxFit arx = fitSegmentArx(u, y, u0, y0, order);
  fit.pole_std_error = std::sqrt(arx.covariance.diagonal().head(order).maxCoeff());
  fit.snr = arx.amplitude / std::max(std::sqrt(arx.sigma2), 1e-300);
  fit.poles = arxPoles(arx.theta, order);
  const double den = 1.0 - arx.theta.head(order).sum();
  fit.gain = std::abs(den) > 1e-12 ? arx.theta.tail(order).sum() / den : INFINITY;
  judgeFit(fit, order, max_std_error, min_snr);
  return fit;
}

}  // namespace plsa::identify
