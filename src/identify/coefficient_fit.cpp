#include "plsa/identify/coefficient_fit.hpp"

#include <climits>
#include <cmath>

namespace plsa {
namespace {

// Steps between two regions: cell moves per scheduling input plus direction flips.
int regionDistance(const PwlPartition& p, int a, int b) {
  int d = 0;
  for (std::size_t s = 0; s < p.inputs().size(); ++s) {
    d += std::abs(p.cellOf(a, s) - p.cellOf(b, s));
    d += p.fallingOf(a, s) != p.fallingOf(b, s) ? 1 : 0;
  }
  return d;
}

}  // namespace

CoefficientFitReport fitCoefficients(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                                     const std::vector<Eigen::MatrixXd>& Y_logged, const CoefficientFitOptions& o) {
  require(!U.empty() && U.size() == Y_logged.size(), "fitCoefficients: need matching input and output records");
  const std::vector<Eigen::MatrixXd> Y = toModelFrame(model.output_frame, Y_logged);
  const int R = model.partition.regionCount();
  const int ny = model.outputCount();
  std::vector<std::vector<Eigen::MatrixXd>> G(static_cast<std::size_t>(ny));
  std::vector<std::vector<Eigen::VectorXd>> h(static_cast<std::size_t>(ny));
  for (int out = 0; out < ny; ++out) {
    const int n = model.regressorSize(out);
    G[static_cast<std::size_t>(out)].assign(static_cast<std::size_t>(R), Eigen::MatrixXd::Zero(n, n));
    h[static_cast<std::size_t>(out)].assign(static_cast<std::size_t>(R), Eigen::VectorXd::Zero(n));
  }
  model.output_level.clear();  // it belongs to the old coefficients
  const bool input_side = model.schedule_side == ScheduleSide::kInput;
  const bool joint = model.partition.scheduling() == Scheduling::kInterpolated || input_side;
  // Interpolated: samples couple neighbouring nodes, so each output is one
  // joint least-squares problem over all regions; switched: independent blocks.
  std::vector<Eigen::MatrixXd> J(static_cast<std::size_t>(ny));
  std::vector<Eigen::VectorXd> Jh(static_cast<std::size_t>(ny));
  if (joint)
    for (int out = 0; out < ny; ++out) {
      const int n = model.regressorSize(out);
      J[static_cast<std::size_t>(out)] = Eigen::MatrixXd::Zero(R * n, R * n);
      Jh[static_cast<std::size_t>(out)] = Eigen::VectorXd::Zero(R * n);
    }
  std::vector<double> count(static_cast<std::size_t>(R), 0.0);
  for (std::size_t r = 0; r < U.size(); ++r) {
    require(U[r].cols() == model.inputCount() && Y[r].cols() == ny && U[r].rows() == Y[r].rows(),
            "fitCoefficients: record " + std::to_string(r) + " does not match the model's inputs and outputs");
    require(Y[r].allFinite(), "fitCoefficients: record " + std::to_string(r) + " has NaN or Inf outputs");
    const ModelRegressors reg = modelRegressors(model, U[r]);
    for (Eigen::Index k = 1; k < U[r].rows(); ++k) {
      const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k)];
      for (int m = 0; m < b.count; ++m)
        count[static_cast<std::size_t>(b.region[static_cast<std::size_t>(m)])] += b.weight[static_cast<std::size_t>(m)];
    }
    if (input_side) {
      // Every node's regressors side by side: one dense least-squares problem.
      const Eigen::Index T = U[r].rows();
      if (T < 2) continue;
      for (int out = 0; out < ny; ++out) {
        const auto oo = static_cast<std::size_t>(out);
        const auto P = reg.phi[oo].bottomRows(T - 1);
        const Eigen::VectorXd dy = Y[r].col(out).tail(T - 1) - Y[r].col(out).head(T - 1);
        J[oo].selfadjointView<Eigen::Lower>().rankUpdate(P.transpose());
        Jh[oo].noalias() += P.transpose() * dy;
      }
      continue;
    }
    for (Eigen::Index k = 1; k < U[r].rows(); ++k) {
      const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k)];
      for (int out = 0; out < ny; ++out) {
        const auto oo = static_cast<std::size_t>(out);
        const auto phi = reg.phi[oo].row(k).transpose();
        const double dy = Y[r](k, out) - Y[r](k - 1, out);
        const Eigen::MatrixXd outer = phi * phi.transpose();
        const Eigen::Index n = phi.size();
        for (int a = 0; a < b.count; ++a) {
          const auto ra = static_cast<std::size_t>(b.region[static_cast<std::size_t>(a)]);
          const double wa = b.weight[static_cast<std::size_t>(a)];
          G[oo][ra] += wa * wa * outer;
          h[oo][ra] += wa * dy * phi;
          if (!joint) continue;
          Jh[oo].segment(static_cast<Eigen::Index>(ra) * n, n) += wa * dy * phi;
          for (int c = 0; c < b.count; ++c) {
            const auto rc = static_cast<std::size_t>(b.region[static_cast<std::size_t>(c)]);
            J[oo].block(static_cast<Eigen::Index>(ra) * n, static_cast<Eigen::Index>(rc) * n, n, n) +=
                wa * b.weight[static_cast<std::size_t>(c)] * outer;
          }
        }
      }
    }
  }
  if (input_side)
    for (int out = 0; out < ny; ++out) {
      const auto oo = static_cast<std::size_t>(out);
      const int n = model.regressorSize(out);
      J[oo] = Eigen::MatrixXd(J[oo].selfadjointView<Eigen::Lower>());
      for (int l = 0; l < R; ++l) G[oo][static_cast<std::size_t>(l)] = J[oo].block(l * n, l * n, n, n);
    }
  model.coefficients.assign(static_cast<std::size_t>(R), std::vector<Eigen::VectorXd>(static_cast<std::size_t>(ny)));
  model.region_fits.assign(static_cast<std::size_t>(R), RegionFit{});
  std::vector<bool> own(static_cast<std::size_t>(R), false);
  int max_params = 0;
  for (int out = 0; out < ny; ++out) max_params = std::max(max_params, model.regressorSize(out));
  for (int l = 0; l < R; ++l) {
    own[static_cast<std::size_t>(l)] = count[static_cast<std::size_t>(l)] >= o.min_samples_per_parameter * max_params;
    model.region_fits[static_cast<std::size_t>(l)].samples = static_cast<int>(std::lround(count[static_cast<std::size_t>(l)]));
  }
  std::vector<Eigen::VectorXd> global(static_cast<std::size_t>(ny));
  for (int out = 0; out < ny; ++out) {
    const auto oo = static_cast<std::size_t>(out);
    const int n = model.regressorSize(out);
    Eigen::MatrixXd Gs = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd hs = Eigen::VectorXd::Zero(n);
    for (int l = 0; l < R; ++l) {
      Gs += G[oo][static_cast<std::size_t>(l)];
      hs += h[oo][static_cast<std::size_t>(l)];
    }
    require(Gs.trace() > 0, "fitCoefficients: the inputs never move, nothing to fit");
    const double scale = Gs.trace() / n;
    Gs.diagonal().array() += o.ridge * scale;
    if (!joint) {
      global[oo] = Gs.ldlt().solve(hs);
    } else {
      // The global solution of the blended model is the one with all nodes equal.
      Eigen::MatrixXd Gsum = Eigen::MatrixXd::Zero(n, n);
      for (int a = 0; a < R; ++a)
        for (int c = 0; c < R; ++c) Gsum += J[oo].block(a * n, c * n, n, n);
      Eigen::VectorXd hsum = Eigen::VectorXd::Zero(n);
      for (int a = 0; a < R; ++a) hsum += Jh[oo].segment(a * n, n);
      Gsum.diagonal().array() += o.ridge * scale;
      global[oo] = Gsum.ldlt().solve(hsum);
    }
    if (joint) {
      for (int l = 0; l < R; ++l) {
        const double sl = std::max(G[oo][static_cast<std::size_t>(l)].trace() / n, 1e-12 * scale);
        const double w = o.pull_to_global * (own[static_cast<std::size_t>(l)] ? sl : scale);
        J[oo].block(l * n, l * n, n, n).diagonal().array() += w;
        Jh[oo].segment(l * n, n) += w * global[oo];
      }
      const Eigen::VectorXd c = J[oo].ldlt().solve(Jh[oo]);
      for (int l = 0; l < R; ++l) model.coefficients[static_cast<std::size_t>(l)][oo] = c.segment(l * n, n);
      continue;
    }
    for (int l = 0; l < R; ++l) {
      const auto ll = static_cast<std::size_t>(l);
      if (!own[ll]) continue;
      Eigen::MatrixXd Gl = G[oo][ll];
      const double s = std::max(Gl.trace() / n, 1e-12 * scale);
      Gl.diagonal().array() += o.pull_to_global * s;
      model.coefficients[ll][oo] = Gl.ldlt().solve(h[oo][ll] + o.pull_to_global * s * global[oo]);
    }
  }
  CoefficientFitReport report;
  for (int l = 0; l < R; ++l) {
    const auto ll = static_cast<std::size_t>(l);
    if (own[ll]) {
      ++report.regions_fitted;
      continue;
    }
    ++report.regions_fallback;
    int best = INT_MAX;
    std::vector<int> nearest;
    for (int m = 0; m < R; ++m) {
      if (!own[static_cast<std::size_t>(m)]) continue;
      const int d = regionDistance(model.partition, l, m);
      if (d < best) {
        best = d;
        nearest.clear();
      }
      if (d == best) nearest.push_back(m);
    }
    RegionFit& fit = model.region_fits[ll];
    const std::string where = model.partition.describe(l, model.inputs);
    if (nearest.empty()) {
      for (int out = 0; out < ny; ++out) model.coefficients[ll][static_cast<std::size_t>(out)] = global[static_cast<std::size_t>(out)];
      fit.fallback_from = -2;
      fit.note = "too little data (" + std::to_string(fit.samples) + " samples): global linear coefficients";
    } else {
      for (int out = 0; out < ny; ++out) {
        Eigen::VectorXd acc = Eigen::VectorXd::Zero(model.regressorSize(out));
        for (int m : nearest) acc += model.coefficients[static_cast<std::size_t>(m)][static_cast<std::size_t>(out)];
        model.coefficients[ll][static_cast<std::size_t>(out)] = acc / static_cast<double>(nearest.size());
      }
      fit.fallback_from = nearest.front();
      fit.note = "too little data (" + std::to_string(fit.samples) + " samples): mean of " +
                 std::to_string(nearest.size()) + " nearest fitted region(s), first " + std::to_string(nearest.front());
    }
    report.notes.push_back("region " + std::to_string(l) + " (" + where + "): " + fit.note);
  }
  return report;
}

void fitOutputLevel(DioPwlObfModel& model, const std::vector<Eigen::MatrixXd>& U,
                    const std::vector<Eigen::MatrixXd>& Y_logged) {
  require(model.schedule_side == ScheduleSide::kInput, "fitOutputLevel: needs an input-side model");
  require(!U.empty() && U.size() == Y_logged.size(), "fitOutputLevel: need matching input and output records");
  const std::vector<Eigen::MatrixXd> Y = toModelFrame(model.output_frame, Y_logged);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(model.outputCount());
  double n = 0.0;
  for (std::size_t r = 0; r < U.size(); ++r) {
    require(Y[r].cols() == model.outputCount() && Y[r].rows() == U[r].rows() && Y[r].allFinite(),
            "fitOutputLevel: record " + std::to_string(r) + " does not match the model's outputs or has NaN");
    if (U[r].rows() == 0) continue;
    sum += (Y[r] - modelLevels(model, U[r])).colwise().sum().transpose();
    n += static_cast<double>(U[r].rows());
  }
  require(n > 0, "fitOutputLevel: no samples");
  model.output_level.resize(static_cast<std::size_t>(model.outputCount()));
  for (int o = 0; o < model.outputCount(); ++o) model.output_level[static_cast<std::size_t>(o)] = sum(o) / n;
}

}  // namespace plsa
