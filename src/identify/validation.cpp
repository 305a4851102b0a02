#include "plsa/identify/validation.hpp"

#include <limits>
#include <tuple>
#include <utility>

#include "plsa/eval/dio_prediction.hpp"

namespace plsa {

std::vector<AlignedPrediction> simulateModel(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                             const Eigen::MatrixXd& y, const Eigen::MatrixXd& dy) {
  require(y.cols() == model.outputCount() && dy.cols() == model.outputCount() && y.rows() == u.rows() &&
              dy.rows() == u.rows(),
          "simulateModel: the record does not match the model's outputs");
  std::vector<AlignedPrediction> out;
  if (model.output_level.empty()) {
    for (int o = 0; o < model.outputCount(); ++o) out.push_back(simulate(y.col(o), dy.col(o)));
    return out;
  }
  require(u.rows() >= 2, "simulateModel: need at least two samples");
  const Eigen::MatrixXd level = modelLevels(model, u, dy);
  for (int o = 0; o < model.outputCount(); ++o) {
    AlignedPrediction p;
    p.first = 1;
    p.values = level.col(o).tail(u.rows() - 1).array() + model.output_level[static_cast<std::size_t>(o)];
    out.push_back(std::move(p));
  }
  return out;
}

namespace {

// A tip_cartesian pair of predictions back to bending and steering;
// `reference(t)` is the steering angle whose branch sample t takes.
template <class Reference>
std::pair<AlignedPrediction, AlignedPrediction> toTipAngles(const AlignedPrediction& x, const AlignedPrediction& y,
                                                            Reference reference) {
  std::pair<AlignedPrediction, AlignedPrediction> out{x, y};
  for (Eigen::Index i = 0; i < x.values.size(); ++i)
    tipAngles(x.values(i), y.values(i), reference(x.first + i, i == 0 ? 0.0 : out.second.values(i - 1)),
              out.first.values(i), out.second.values(i));
  return out;
}

}  // namespace

std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation) {
  return predictOutputs(model, u, y, horizons, with_simulation, modelIncrements(model, u));
}

std::vector<std::map<int, AlignedPrediction>> predictOutputs(const DioPwlObfModel& model, const Eigen::MatrixXd& u,
                                                             const Eigen::MatrixXd& y, const std::vector<int>& horizons,
                                                             bool with_simulation, const Eigen::MatrixXd& dy) {
  require(y.cols() == model.outputCount() && y.rows() == u.rows(),
          "predictOutputs: the record does not match the model's outputs");
  require(dy.rows() == u.rows() && dy.cols() == model.outputCount(),
          "predictOutputs: the increments do not match the record");
  const Eigen::MatrixXd ym = toModelFrame(model.output_frame, y);
  std::vector<std::map<int, AlignedPrediction>> out(static_cast<std::size_t>(model.outputCount()));
  for (int k : horizons) {
    require(k >= 1, "validate: horizons must be >= 1, got " + std::to_string(k));
    for (int o = 0; o < model.outputCount(); ++o) out[static_cast<std::size_t>(o)][k] = kStepAhead(ym.col(o), dy.col(o), k);
    if (model.output_frame == OutputFrame::kTipCartesian)
      std::tie(out[0][k], out[1][k]) =
          toTipAngles(out[0][k], out[1][k], [&](Eigen::Index t, double) { return y(t - k, 1); });
  }
  if (with_simulation) {
    const std::vector<AlignedPrediction> sims = simulateModel(model, u, ym, dy);
    for (int o = 0; o < model.outputCount(); ++o) out[static_cast<std::size_t>(o)][0] = sims[static_cast<std::size_t>(o)];
    if (model.output_frame == OutputFrame::kTipCartesian)
      std::tie(out[0][0], out[1][0]) = toTipAngles(out[0][0], out[1][0], [&](Eigen::Index t, double previous) {
        return t == sims[0].first ? y(0, 1) : previous;
      });
  }
  return out;
}

ValidationResult validateModel(const DioPwlObfModel& model, const io::Log& log, const std::vector<int>& horizons) {
  require(!horizons.empty(), "validate: no horizons given");
  const Eigen::MatrixXd u = log.columnsOf(model.inputs);
  const Eigen::MatrixXd y = log.columnsOf(model.outputs);
  const std::vector<std::map<int, AlignedPrediction>> pred = predictOutputs(model, u, y, horizons);
  ValidationResult res;
  res.time = log.hasColumn("time_s") ? log.column("time_s") : Eigen::VectorXd::LinSpaced(u.rows(), 0, u.rows() - 1);
  res.input_outside_range =
      static_cast<double>(((u.array() < model.input_min - 1e-9) || (u.array() > model.input_max + 1e-9)).rowwise().any().count()) /
      static_cast<double>(u.rows());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int o = 0; o < model.outputCount(); ++o) {
    OutputValidation ov;
    ov.name = model.outputs[static_cast<std::size_t>(o)];
    ov.measured = y.col(o);
    for (int k : horizons) {
      const AlignedPrediction& p = pred[static_cast<std::size_t>(o)].at(k);
      ov.fit_k[k] = fitOf(ov.measured, p);
      Eigen::VectorXd full = Eigen::VectorXd::Constant(y.rows(), nan);
      full.segment(p.first, p.values.size()) = p.values;
      ov.predicted_k[k] = full;
    }
    const AlignedPrediction& s = pred[static_cast<std::size_t>(o)].at(0);
    ov.fit_sim = fitOf(ov.measured, s);
    ov.simulated = Eigen::VectorXd::Constant(y.rows(), nan);
    ov.simulated.segment(s.first, s.values.size()) = s.values;
    res.outputs.push_back(std::move(ov));
  }
  return res;
}

io::Log predictionLog(const ValidationResult& v) {
  io::Log log;
  log.columns.push_back("time_s");
  int first = 1;
  for (const auto& o : v.outputs) {
    log.columns.push_back(o.name);
    for (const auto& [k, p] : o.predicted_k) {
      log.columns.push_back(o.name + "_k" + std::to_string(k));
      first = std::max(first, k);
    }
    log.columns.push_back(o.name + "_sim");
  }
  const Eigen::Index T = v.time.size() - first;
  log.data.resize(T, static_cast<Eigen::Index>(log.columns.size()));
  Eigen::Index c = 0;
  log.data.col(c++) = v.time.tail(T);
  for (const auto& o : v.outputs) {
    log.data.col(c++) = o.measured.tail(T);
    for (const auto& [k, p] : o.predicted_k) log.data.col(c++) = p.tail(T);
    log.data.col(c++) = o.simulated.tail(T);
  }
  log.metadata["source"] = "plsa validate";
  return log;
}

}  // namespace plsa
