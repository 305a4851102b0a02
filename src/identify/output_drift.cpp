#include "plsa/identify/output_drift.hpp"

#include <cmath>
#include <string>

namespace plsa::identify {

double meanSampleTime(const std::vector<Eigen::VectorXd>& t) {
  double sum = 0.0;
  Eigen::Index n = 0;
  for (const Eigen::VectorXd& v : t) {
    sum += v.sum();
    n += v.size();
  }
  PLSA_CHECK(n > 0, "output drift: no sample times");
  return sum / static_cast<double>(n);
}

std::vector<Eigen::MatrixXd> removeOutputDrift(const std::vector<Eigen::MatrixXd>& Y,
                                               const std::vector<Eigen::VectorXd>& t, const OutputDrift& drift) {
  PLSA_CHECK(Y.size() == t.size(), "output drift: need one time vector per record");
  std::vector<Eigen::MatrixXd> out = Y;
  for (std::size_t r = 0; r < Y.size(); ++r) {
    PLSA_CHECK(t[r].size() == Y[r].rows() && static_cast<std::size_t>(Y[r].cols()) == drift.rate.size(),
               "output drift: record " + std::to_string(r) + " does not match the drift's outputs or its times");
    const Eigen::ArrayXd since = t[r].array() - drift.reference_time_s;
    for (Eigen::Index o = 0; o < Y[r].cols(); ++o)
      if (drift.rate[static_cast<std::size_t>(o)] != 0.0)
        out[r].col(o).array() -= drift.rate[static_cast<std::size_t>(o)] * since;
  }
  return out;
}

OutputDrift estimateOutputDrift(const DioPwlObfModel& model_in, const std::vector<Eigen::MatrixXd>& U,
                                const std::vector<Eigen::MatrixXd>& Y, const std::vector<Eigen::VectorXd>& t,
                                const CoefficientFitOptions& options, int iterations, const SampleWeights& weights) {
  PLSA_CHECK(model_in.schedule_side == ScheduleSide::kInput,
             "output drift: needs an input-side model (only its level is a function of the inputs)");
  PLSA_CHECK(U.size() == Y.size() && U.size() == t.size() && !U.empty(),
             "output drift: need matching records and times");
  PLSA_CHECK(iterations >= 1, "output drift: need at least one iteration");
  checkSampleWeights(U, weights, "output drift");
  const int ny = model_in.outputCount();
  const bool tip = model_in.output_frame == OutputFrame::kTipCartesian;
  const double rad_per_unit = tip ? model_in.radiansPerAngleUnit() : 1.0;
  OutputDrift drift;
  drift.rate.assign(static_cast<std::size_t>(ny), 0.0);
  drift.reference_time_s = meanSampleTime(t);
  DioPwlObfModel model = model_in;
  for (int it = 0; it < iterations; ++it) {
    const std::vector<Eigen::MatrixXd> Yc = removeOutputDrift(Y, t, drift);
    fitCoefficients(model, U, Yc, options, weights);
    fitOutputLevel(model, U, Yc, weights);
    // Residual and signature, model frame, with their means taken out per
    // output (the level absorbs any constant).
    std::vector<double> zz(static_cast<std::size_t>(ny), 0.0), zr(static_cast<std::size_t>(ny), 0.0);
    std::vector<double> sz(static_cast<std::size_t>(ny), 0.0), sr(static_cast<std::size_t>(ny), 0.0);
    double n = 0.0;
    for (std::size_t r = 0; r < U.size(); ++r) {
      if (U[r].rows() == 0) continue;
      const Eigen::MatrixXd ym = model.toModelFrame(Yc[r]);
      const Eigen::MatrixXd level = eval::modelLevels(model, U[r], eval::modelIncrements(model, U[r]));
      const Eigen::ArrayXd since = t[r].array() - drift.reference_time_s;
      for (Eigen::Index k = 0; k < ym.rows(); ++k) {
        const double w = weights.empty() ? 1.0 : weights[r](k);
        if (w == 0.0) continue;
        for (int o = 0; o < ny; ++o) {
          const auto oo = static_cast<std::size_t>(o);
          const double res = ym(k, o) - model.output_level[oo] - level(k, o);
          // A yaw of d (the steering's unit) turns (x, y) by d: dx = -y d, dy = x d (radians).
          const double z = !tip ? since(k) : (o == 0 ? -ym(k, 1) : ym(k, 0)) * rad_per_unit * since(k);
          zz[oo] += w * z * z;
          zr[oo] += w * z * res;
          sz[oo] += w * z;
          sr[oo] += w * res;
        }
        n += w;
      }
    }
    for (int o = 0; o < ny; ++o) {
      const auto oo = static_cast<std::size_t>(o);
      zz[oo] -= sz[oo] * sz[oo] / n;
      zr[oo] -= sz[oo] * sr[oo] / n;
    }
    // No signature (a tip at the origin, logs without a time span): no drift to see, none taken.
    if (tip) {
      const double den = zz[0] + zz[1];
      if (den > 0) drift.rate[1] += (zr[0] + zr[1]) / den;
    } else {
      for (int o = 0; o < ny; ++o) {
        const auto oo = static_cast<std::size_t>(o);
        if (zz[oo] > 0) drift.rate[oo] += zr[oo] / zz[oo];
      }
    }
  }
  return drift;
}

}  // namespace plsa::identify
