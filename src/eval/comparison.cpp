#include "plsa/eval/comparison.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "plsa/core/check.hpp"
#include "plsa/eval/dio_prediction.hpp"
#include "plsa/eval/fit.hpp"

namespace plsa::eval {

ModelPredictions predictDio(const std::string& name, const DioPwlObfModel& m, const Eigen::MatrixXd& u,
                            const Eigen::MatrixXd& y, const std::vector<int>& horizons, const SimulationStart& start) {
  const std::vector<std::map<int, AlignedPrediction>> pred = predictOutputs(m, u, y, horizons, true, start);
  ModelPredictions out{name, {}};
  for (const auto& by_horizon : pred) {
    std::map<int, Eigen::VectorXd> byh;
    for (const auto& [k, p] : by_horizon) byh[k] = placedOver(p, y.rows());
    out.by_output.push_back(std::move(byh));
  }
  return out;
}

ModelPredictions predictArx(const std::string& name, const ArxModel& m, const Eigen::MatrixXd& u,
                            const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                            const std::vector<double>& sim_drift_per_s, double sample_time_s) {
  PLSA_CHECK(sim_drift_per_s.empty() || (static_cast<Eigen::Index>(sim_drift_per_s.size()) == y.cols() &&
                                         std::isfinite(sample_time_s) && sample_time_s > 0),
             "predictArx: need one drift rate per output and a sample time > 0");
  ModelPredictions out{name, {}};
  for (Eigen::Index o = 0; o < y.cols(); ++o) {
    std::map<int, Eigen::VectorXd> byh;
    for (int k : horizons) byh[k] = placedOver(m.kStepAhead(u, y.col(o), static_cast<int>(o), k), y.rows());
    byh[0] = placedOver(m.simulate(u, y.col(o), static_cast<int>(o)), y.rows());
    if (!sim_drift_per_s.empty())
      byh[0] += sim_drift_per_s[static_cast<std::size_t>(o)] * sample_time_s *
                Eigen::VectorXd::LinSpaced(y.rows(), 0.0, static_cast<double>(y.rows() - 1));
    out.by_output.push_back(std::move(byh));
  }
  return out;
}

Eigen::Index commonScoringStart(const std::vector<ModelPredictions>& models) {
  Eigen::Index from = 0;
  for (const auto& m : models)
    for (const auto& by_horizon : m.by_output)
      for (const auto& [k, p] : by_horizon) {
        (void)k;
        Eigen::Index f = 0;
        while (f < p.size() && !std::isfinite(p(f))) ++f;
        from = std::max(from, f);
      }
  return from;
}

std::vector<std::vector<std::map<int, CommonScore>>> commonScores(const std::vector<ModelPredictions>& models,
                                                                  const Eigen::MatrixXd& y) {
  const Eigen::Index from = commonScoringStart(models), n = y.rows() - from;
  PLSA_CHECK(n >= 2, "commonScores: " + std::to_string(y.rows()) + " samples leave " +
                         std::to_string(std::max<Eigen::Index>(n, 0)) +
                         " to score after every model's longest horizon; a fit needs 2");
  std::vector<std::vector<std::map<int, CommonScore>>> scores(models.size());
  for (std::size_t i = 0; i < models.size(); ++i) {
    scores[i].resize(static_cast<std::size_t>(y.cols()));
    for (Eigen::Index o = 0; o < y.cols(); ++o) {
      const Eigen::VectorXd measured = y.col(o).segment(from, n);
      for (const auto& [k, p] : models[i].by_output[static_cast<std::size_t>(o)]) {
        const Eigen::VectorXd predicted = p.segment(from, n);
        scores[i][static_cast<std::size_t>(o)][k] = {nrmseFit(measured, predicted), rmsError(measured, predicted),
                                                     spreadOf(measured)};
      }
    }
  }
  return scores;
}

}  // namespace plsa::eval
