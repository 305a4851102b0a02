#include "plsa/eval/arx.hpp"

#include <algorithm>

#include "plsa/core/check.hpp"

namespace plsa::eval {
namespace {

int lag(const ArxModel& m) { return std::max(m.na, m.nb); }

// One-step value of output o at time t from a y history accessor and the inputs.
template <class YAt>
double arxStep(const ArxModel& m, const Eigen::MatrixXd& u, int o, Eigen::Index t, YAt y_at) {
  const auto th = m.theta.col(o);
  double v = th(th.size() - 1);
  for (int i = 1; i <= m.na; ++i) v += th(i - 1) * y_at(t - i);
  for (Eigen::Index j = 0; j < u.cols(); ++j)
    for (int i = 1; i <= m.nb; ++i) v += th(m.na + j * m.nb + i - 1) * u(t - i, j);
  return v;
}

}  // namespace

ArxModel ArxModel::fit(const std::vector<Eigen::MatrixXd>& U, const std::vector<Eigen::MatrixXd>& Y, int na, int nb,
                       double ridge) {
  PLSA_CHECK(na >= 0 && nb >= 1, "ArxModel::fit: need na >= 0 and nb >= 1");
  PLSA_CHECK(!U.empty() && U.size() == Y.size(), "ArxModel::fit: need matching input and output records");
  ArxModel m;
  m.na = na;
  m.nb = nb;
  const Eigen::Index nu = U[0].cols(), ny = Y[0].cols();
  const Eigen::Index p = na + nu * nb + 1;
  m.theta.resize(p, ny);
  for (Eigen::Index o = 0; o < ny; ++o) {
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(p, p);
    Eigen::VectorXd h = Eigen::VectorXd::Zero(p);
    for (std::size_t r = 0; r < U.size(); ++r) {
      PLSA_CHECK(U[r].cols() == nu && Y[r].cols() == ny && U[r].rows() == Y[r].rows(),
                 "ArxModel::fit: record " + std::to_string(r) + " has a different shape");
      Eigen::VectorXd phi(p);
      for (Eigen::Index t = lag(m); t < U[r].rows(); ++t) {
        for (int i = 1; i <= na; ++i) phi(i - 1) = Y[r](t - i, o);
        for (Eigen::Index j = 0; j < nu; ++j)
          for (int i = 1; i <= nb; ++i) phi(na + j * nb + i - 1) = U[r](t - i, j);
        phi(p - 1) = 1.0;
        G.noalias() += phi * phi.transpose();
        h.noalias() += phi * Y[r](t, o);
      }
    }
    G.diagonal().array() += ridge * std::max(1.0, G.trace() / static_cast<double>(p));
    m.theta.col(o) = G.ldlt().solve(h);
  }
  return m;
}

AlignedPrediction ArxModel::kStepAhead(const Eigen::MatrixXd& u, const Eigen::VectorXd& y, int o, int k) const {
  PLSA_CHECK(k >= 1, "ArxModel::kStepAhead: horizon must be >= 1");
  const Eigen::Index L = lag(*this), T = y.size();
  PLSA_CHECK(T > L + k, "ArxModel::kStepAhead: log shorter than lag + horizon");
  AlignedPrediction out;
  out.first = L + k - 1;
  out.values.resize(T - out.first);
  std::vector<double> pred(static_cast<std::size_t>(k));
  for (Eigen::Index t0 = L - 1; t0 + k < T; ++t0) {
    // Measured up to t0, predict t0+1..t0+k.
    for (int s = 1; s <= k; ++s) {
      const Eigen::Index t = t0 + s;
      pred[static_cast<std::size_t>(s - 1)] = arxStep(
          *this, u, o, t, [&](Eigen::Index q) { return q <= t0 ? y(q) : pred[static_cast<std::size_t>(q - t0 - 1)]; });
    }
    out.values(t0 + k - out.first) = pred[static_cast<std::size_t>(k - 1)];
  }
  // The last index t0 + k = T - 1 is covered; size check:
  return out;
}

AlignedPrediction ArxModel::simulate(const Eigen::MatrixXd& u, const Eigen::VectorXd& y, int o) const {
  const Eigen::Index L = lag(*this), T = y.size();
  PLSA_CHECK(T > L + 1, "ArxModel::simulate: log shorter than the model's lag");
  Eigen::VectorXd sim = y;
  for (Eigen::Index t = L; t < T; ++t) sim(t) = arxStep(*this, u, o, t, [&](Eigen::Index q) { return sim(q); });
  AlignedPrediction out;
  out.first = L;
  out.values = sim.tail(T - L);
  return out;
}

}  // namespace plsa::eval
