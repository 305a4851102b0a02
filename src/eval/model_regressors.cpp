// Batch regressors, increments and levels of a DIO-PWL-OBF model over whole
// input records (model_regressors.hpp): offline only, the real-time
// predictor never runs them.
#include "plsa/eval/model_regressors.hpp"

#include <algorithm>
#include <exception>
#include <limits>

#include "plsa/core/parallel_for.hpp"
#include "plsa/obf/obf_bank.hpp"

namespace plsa::eval {

namespace {

// Each sample's schedule: the blend of the inputs up to k-1 through the lag
// (which starts settled at the first input), with the directions of change.
// Input side: each sample's own lagged input instead (the output side's
// schedule of sample k+1), and the node weights it gives, one column per
// region (empty on the output side).
Eigen::MatrixXd scheduleSamples(ModelRegressors& out, const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  const PwlPartition& partition = model.partition;
  const double schedule_pole = model.schedulePole();
  const Eigen::Index T = u.rows();
  out.schedule.resize(static_cast<std::size_t>(T));
  DirectionState dir;
  Eigen::RowVectorXd du = Eigen::RowVectorXd::Zero(u.cols());
  Eigen::RowVectorXd lagged = T > 0 ? u.row(0) : Eigen::RowVectorXd();
  for (Eigen::Index k = 0; k < T; ++k) {
    const Eigen::Index prev = k == 0 ? 0 : k - 1;
    if (k >= 2) du = u.row(k - 1) - u.row(k - 2);
    if (k >= 2) partition.updateDirections(du, dir);
    if (k >= 2) lagged = schedule_pole * lagged + (1.0 - schedule_pole) * u.row(prev);
    partition.blend(lagged, dir, out.schedule[static_cast<std::size_t>(k)]);
  }
  if (model.schedule_side != ScheduleSide::kInput) return {};
  Eigen::MatrixXd node_weight = Eigen::MatrixXd::Zero(T, partition.regionCount());
  for (Eigen::Index k = 0; k < T; ++k) {
    ScheduleBlend& b = out.schedule[static_cast<std::size_t>(k)];
    if (k + 1 < T)
      b = out.schedule[static_cast<std::size_t>(k + 1)];
    else if (k > 0)
      partition.blend((schedule_pole * lagged + (1.0 - schedule_pole) * u.row(k)).eval(), dir, b);
  }
  for (Eigen::Index k = 0; k < T; ++k) {
    const ScheduleBlend& b = out.schedule[static_cast<std::size_t>(k)];
    for (int m = 0; m < b.count; ++m)
      node_weight(k, b.region[static_cast<std::size_t>(m)]) += b.weight[static_cast<std::size_t>(m)];
  }
  return node_weight;
}

// Channel inputs: input j's shaped level through each of its play channels.
std::vector<std::vector<Eigen::VectorXd>> channelInputs(const InputShaping& shaping, const Eigen::MatrixXd& u) {
  const auto n_u = static_cast<std::size_t>(u.cols());
  PLSA_CHECK(shaping.play.empty() || shaping.play.size() == n_u, "modelRegressors: need one play list per input");
  Eigen::MatrixXd coupled;
  const bool shaped = shaping.shapesLevels();
  if (shaped) {
    coupled.resize(u.rows(), u.cols());
    for (Eigen::Index k = 0; k < u.rows(); ++k) {
      const double positive_sum = shaping.positiveSum(u.row(k));
      for (Eigen::Index j = 0; j < u.cols(); ++j) coupled(k, j) = shaping.level(u(k, j), positive_sum);
    }
  }
  const Eigen::MatrixXd& level = shaped ? coupled : u;
  std::vector<std::vector<Eigen::VectorXd>> channels(n_u);
  for (std::size_t j = 0; j < n_u; ++j) {
    const std::vector<PlayChannel> list =
        shaping.play.empty() ? std::vector<PlayChannel>{PlayChannel{}} : shaping.play[j];
    for (const PlayChannel& ch : list)
      channels[j].push_back(playedInput(level.col(static_cast<Eigen::Index>(j)), ch, shaping.start));
  }
  return channels;
}

// One output's regressors: every input's bank on each of its channels, a
// column block per copy (input side: per node, the channel weighted by the
// node; output side: one copy).
struct OutputFill {
  const std::vector<std::vector<Eigen::VectorXd>>& channels;
  const Eigen::MatrixXd& node_weight;  ///< empty on the output side
  int copies = 1;
  Eigen::Index T = 0;

  // The filters run on every copy at once, a state row per copy: the copies'
  // recursions are independent, so the loop over them vectorises. Raw loops:
  // at five or six states Eigen's dynamic expressions cost more than the
  // arithmetic. Writes columns offset .. offset + n - 1 of each copy's block.
  template <typename Drive>
  void filterChannel(const ObfBank<>& bank, Drive f, double* phi, int width, int offset) const {
    const int n = bank.size();
    const Eigen::MatrixXd& A = bank.A();
    const Eigen::VectorXd& B = bank.B();
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(copies, n), next(copies, n);
    Eigen::VectorXd step_in(copies);  // each copy's input increment
    double* now = x.data();
    double* then = next.data();
    double* const col0 = phi + static_cast<Eigen::Index>(offset) * T;
    for (Eigen::Index k = 0; k < T; ++k) {
      for (int i = 0; i < n; ++i)
        for (int r = 0; r < copies; ++r) col0[(static_cast<Eigen::Index>(r) * width + i) * T + k] = now[i * copies + r];
      for (int r = 0; r < copies; ++r) step_in(r) = k == 0 ? 0.0 : f(k, r) - f(k - 1, r);
      for (int i = 0; i < n; ++i) {
        double* const to = then + i * copies;
        for (int r = 0; r < copies; ++r) to[r] = B(i) * step_in(r);
        for (int l = 0; l < n; ++l) {
          const double a = A(i, l);
          if (a == 0.0) continue;
          const double* const from = now + l * copies;
          for (int r = 0; r < copies; ++r) to[r] += a * from[r];
        }
      }
      std::swap(now, then);
    }
  }

  void fill(const std::vector<PoleSet>& row, bool input_side, Eigen::MatrixXd& phi, Eigen::RowVectorXd& level0) const {
    int width = 0;
    for (std::size_t j = 0; j < row.size(); ++j) width += row[j].size() * static_cast<int>(channels[j].size());
    phi.resize(T, width * copies);
    if (input_side) level0.setZero(width * copies);
    int offset = 0;
    for (std::size_t j = 0; j < row.size(); ++j) {
      const ObfBank<> bank(row[j]);
      const Eigen::RowVectorXd gain = bank.transfer(1.0).real().transpose();
      for (const Eigen::VectorXd& v : channels[j]) {
        auto f = [&](Eigen::Index k, int r) { return input_side ? node_weight(k, r) * v(k) : v(k); };
        filterChannel(bank, f, phi.data(), width, offset);
        if (input_side && T > 0)
          for (int r = 0; r < copies; ++r)
            level0.segment(static_cast<Eigen::Index>(r) * width + offset, bank.size()) = gain * f(0, r);
        offset += bank.size();
      }
    }
  }
};

// Input side: which tiles of rows move each copy's columns at all (the
// coefficient fit skips the rest).
void markLiveTiles(const Eigen::MatrixXd& phi, int copies, Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic>& live) {
  const Eigen::Index T = phi.rows(), tile = ModelRegressors::kTileRows;
  const Eigen::Index width = copies > 0 ? phi.cols() / copies : 0;
  live.resize((T + tile - 1) / tile, copies);
  if (T == 0) return;
  const Eigen::RowVectorXd negligible = std::numeric_limits<double>::epsilon() * phi.cwiseAbs().colwise().maxCoeff();
  for (Eigen::Index t = 0; t < live.rows(); ++t)
    for (int r = 0; r < copies; ++r)
      live(t, r) = (phi.block(t * tile, static_cast<Eigen::Index>(r) * width, std::min(tile, T - t * tile), width)
                        .cwiseAbs()
                        .colwise()
                        .maxCoeff()
                        .array() > negligible.segment(static_cast<Eigen::Index>(r) * width, width).array())
                       .any();
}

void fillRegressors(ModelRegressors& out, const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  PLSA_CHECK(!model.poles.empty(), "modelRegressors: no outputs");
  PLSA_CHECK(u.allFinite(), "modelRegressors: the inputs contain NaN or Inf");
  const bool input_side = model.schedule_side == ScheduleSide::kInput;
  const Eigen::MatrixXd node_weight = scheduleSamples(out, model, u);
  const std::vector<std::vector<Eigen::VectorXd>> channels = channelInputs(model.shaping, u);
  for (const auto& row : model.poles)
    PLSA_CHECK(row.size() == static_cast<std::size_t>(u.cols()), "modelRegressors: need one pole set per input");
  const OutputFill filler{channels, node_weight, input_side ? model.partition.regionCount() : 1, u.rows()};
  const std::size_t outputs = model.poles.size();
  out.phi.resize(outputs);
  out.level0.resize(input_side ? outputs : 0);
  out.live.resize(input_side ? outputs : 0);
  Eigen::RowVectorXd unused;  // the output side has no level0
  // The outputs' regressors are independent: one thread each, when the
  // record is long enough to pay for them.
  const bool threaded = u.rows() >= 2048;
  parallelFor(outputs, threaded ? static_cast<int>(outputs) : 1, [&](std::size_t o) {
    filler.fill(model.poles[o], input_side, out.phi[o], input_side ? out.level0[o] : unused);
    if (input_side) markLiveTiles(out.phi[o], filler.copies, out.live[o]);
  });
}

}  // namespace

ModelRegressors modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  ModelRegressors out;
  fillRegressors(out, model, u);
  return out;
}

void modelRegressors(const DioPwlObfModel& model, const Eigen::MatrixXd& u, ModelRegressors& out) {
  fillRegressors(out, model, u);
}

Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const ModelRegressors& reg) {
  PLSA_CHECK(reg.phi.size() == static_cast<std::size_t>(model.outputCount()),
             "modelIncrements: the regressors were made for another model");
  const auto T = static_cast<Eigen::Index>(reg.schedule.size());
  Eigen::MatrixXd dy(T, model.outputCount());
  if (model.schedule_side == ScheduleSide::kInput) {
    const Eigen::Index tile = ModelRegressors::kTileRows;
    for (int o = 0; o < model.outputCount(); ++o) {
      const auto oo = static_cast<std::size_t>(o);
      const Eigen::VectorXd c = model.stackedCoefficients(o);
      if (reg.live.empty()) {
        dy.col(o) = reg.phi[oo] * c;
        continue;
      }
      const Eigen::Index width = model.regressorSize(o);
      dy.col(o).setZero();
      for (Eigen::Index t = 0; t < reg.live[oo].rows(); ++t)
        for (Eigen::Index r = 0; r < reg.live[oo].cols(); ++r)
          if (reg.live[oo](t, r)) {
            const Eigen::Index rows = std::min(tile, T - t * tile);
            dy.col(o).segment(t * tile, rows).noalias() +=
                reg.phi[oo].block(t * tile, r * width, rows, width) * c.segment(r * width, width);
          }
    }
    return dy;
  }
  for (Eigen::Index k = 0; k < T; ++k) {
    const ScheduleBlend& b = reg.schedule[static_cast<std::size_t>(k)];
    for (int o = 0; o < model.outputCount(); ++o) {
      double v = 0.0;
      for (int m = 0; m < b.count; ++m)
        v += b.weight[static_cast<std::size_t>(m)] *
             reg.phi[static_cast<std::size_t>(o)].row(k).dot(model.coefficients[static_cast<std::size_t>(
                 b.region[static_cast<std::size_t>(m)])][static_cast<std::size_t>(o)]);
      dy(k, o) = v;
    }
  }
  return dy;
}

Eigen::MatrixXd modelIncrements(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  PLSA_CHECK(u.cols() == model.inputCount(), "modelIncrements: the record has " + std::to_string(u.cols()) +
                                                 " inputs, the model " + std::to_string(model.inputCount()));
  return modelIncrements(model, modelRegressors(model, u));
}

Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u, const Eigen::MatrixXd& dy) {
  PLSA_CHECK(model.schedule_side == ScheduleSide::kInput,
             "modelLevels: only an input-side model has a level that is a function of its inputs");
  PLSA_CHECK(u.rows() >= 1, "modelLevels: empty record");
  PLSA_CHECK(dy.rows() == u.rows() && dy.cols() == model.outputCount(),
             "modelLevels: increments do not match the record");
  // Settled states depend on the first sample alone (its schedule, played and coupled level).
  const ModelRegressors first = modelRegressors(model, u.topRows(1));
  Eigen::MatrixXd level(u.rows(), model.outputCount());
  for (int o = 0; o < model.outputCount(); ++o) {
    double acc = first.level0[static_cast<std::size_t>(o)].dot(model.stackedCoefficients(o));
    level(0, o) = acc;
    for (Eigen::Index k = 1; k < u.rows(); ++k) level(k, o) = acc += dy(k, o);
  }
  return level;
}

Eigen::MatrixXd modelLevels(const DioPwlObfModel& model, const Eigen::MatrixXd& u) {
  return modelLevels(model, u, modelIncrements(model, u));
}

}  // namespace plsa::eval
